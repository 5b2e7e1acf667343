"""An independent CANopen encoder (WDGA multiturn) in its own process, reached only over the bus.

    python -m tests.independent.encoder_device --channel ws://127.0.0.1:PORT/ --node-id 5 \\
        [--break direction|preset|cam-polarity|cam-hysteresis] [--shaft-listen 127.0.0.1:0] [--eds FILE]

The object dictionary is imported from the EDS that ``encoder-conformance profile to-eds`` writes for the
profile (the command runs when ``--eds`` is not given); SDO, heartbeat (1017h) and the NMT states are
python-canopen's ``LocalNode``. Everything an encoder computes is this package's own code
(``encoder_function``), reached through LocalNode's read and write callbacks; nothing of
``encoder_conformance`` is imported. The shaft is turned by the shaft-drive plug-in
(``tests.independent.shaft_link``) through a local link whose address the device prints on its
``READY {json}`` line.

What it adds to LocalNode, each from CiA 301 or the WDGA manual: boot-up and a reload of the stored values
on NMT reset node / reset communication; store (1010h 'save') and restore defaults (1011h 'load', active
after the next reset) in a memory that lives as long as the process, by the manual's groups (all,
communication 1000h-1FFFh, application 6000h-9FFFh, manufacturer 2000h-5FFFh; 2100h, 2101h, 2120h saved on
write and kept by restore); synchronous TPDOs (types 1..240) from the current mapping. Not implemented:
event-driven TPDOs (types 254/255), EMCY, LSS, node-ID/bit-rate changes through 2100h/2101h, refusing SDO in
stopped, the pre-operational-only rules for PDO and CAM settings.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from multiprocessing.connection import Connection, Listener
from pathlib import Path

import canopen
from canopen.objectdictionary import ODVariable
from canopen.objectdictionary.datatypes import NUMBER_TYPES
from canopen.sdo.exceptions import SdoAbortedError

from .encoder_function import (
    BREAKS,
    CAMS,
    CamSettings,
    CamSwitch,
    Sensor,
    Units,
    area_state,
    offset_for_preset,
    shown_position,
    speed_value,
)
from .link import AUTHKEY, COMMANDS, format_address, parse_address, wait_for_sigterm

Key = tuple[int, int]

# CiA 301 (spelled here: the device imports nothing of the project)
SAVE = b"save"  # 1010h signature, bytes 73 61 76 65
LOAD = b"load"  # 1011h signature, bytes 6C 6F 61 64
ABORT_CANNOT_STORE = 0x08000020
ABORT_VALUE_TOO_HIGH = 0x06090031
ABORT_VALUE_TOO_LOW = 0x06090032
ABORT_MAX_BELOW_MIN = 0x06090036
NMT_RESET_NODE, NMT_RESET_COMMUNICATION, NMT_ENTER_PREOPERATIONAL = 0x81, 0x82, 0x80
SYNC_COB_ID = 0x80
COB_ID_INVALID = 1 << 31
STORE, RESTORE = 0x1010, 0x1011
TPDO_COMMUNICATION = (0x1800, 0x1801, 0x1802, 0x1803)
#: 1010h/1011h sub-index -> the objects it covers (WDGA M §8.12: all, communication, application, manufacturer)
GROUPS = {1: (0x1000, 0x9FFF), 2: (0x1000, 0x1FFF), 3: (0x6000, 0x9FFF), 4: (0x2000, 0x5FFF)}
#: saved to EEPROM on every write and kept by restore defaults (WDGA M §4.2, §7.12, §8.12.2)
AUTO_SAVED = (0x2100, 0x2101, 0x2120)

# CiA 406 objects
OPERATING, UNITS_PER_REV, TOTAL_RANGE, PRESET, POSITION = 0x6000, 0x6001, 0x6002, 0x6003, 0x6004
HIGH_PRECISION_POSITION, SPEED = 0x6008, 0x6030
CAM_STATE, CAM_ENABLE, CAM_POLARITY, CAM_LOW, CAM_HIGH, CAM_HYSTERESIS = 0x6300, 0x6301, 0x6302, 0x6310, 0x6320, 0x6330
AREA_STATE, AREA_LOW, AREA_HIGH = 0x6400, 0x6401, 0x6402
OPERATING_STATUS, STEPS_PER_REV, OFFSET, SERIAL = 0x6500, 0x6501, 0x6509, 0x650B
SPEED_SCALING = 0x2106  # WDGA: multiplier / divisor of the speed value (M §8.9)

#: the largest total measuring range of a WDGA that is not a "32-bit device", from revision 1.12 (M §8.6)
MAX_TOTAL_RANGE = 1 << 31
DEFAULT_PROFILE = "wachendorff-wdga-mt"


class Shaft:
    """The encoder's shaft: an angle in revolutions (clockwise positive) that a drive turns or spins."""

    def __init__(self, turns: float, steps_per_rev: int) -> None:
        self._base = turns
        self._speed = 0.0
        self._since = time.monotonic()
        self._steps = steps_per_rev

    def turns(self) -> float:
        return self._base + self._speed * (time.monotonic() - self._since)

    @property
    def speed(self) -> float:
        return self._speed

    def turn_by(self, revolutions: float) -> None:
        self._base, self._since = self.turns() + revolutions, time.monotonic()

    def set_speed(self, revolutions_per_second: float) -> None:
        turns = self.turns()
        if revolutions_per_second == 0.0:  # the drive stops in the middle of a step (no count on a rounding edge)
            turns = (int(turns * self._steps // 1) + 0.5) / self._steps
        self._base, self._since, self._speed = turns, time.monotonic(), revolutions_per_second


class IndependentEncoder:
    """The device: a LocalNode whose encoder objects are computed from the shaft and the settings."""

    def __init__(self, od: canopen.ObjectDictionary, node_id: int, breaks: frozenset[str], per_unit: dict[Key, object],
                 revolutions: int, start_turns: float) -> None:
        self.node = canopen.LocalNode(node_id, od)
        self.node.nmt.update_heartbeat = self._restart_heartbeat  # type: ignore[method-assign]
        self.od = od
        self.breaks = breaks
        self.lock = threading.RLock()
        self.variables = {(v.index, v.subindex): v for v in _variables(od)}
        self.factory = self._factory_values(per_unit)
        self.nvm: dict[Key, bytes] = {}  # what 1010h stored (empty: delivery state)
        self.nvm_offset: int | None = None
        steps = int(self.variables[(STEPS_PER_REV, 0)].default)
        self.sensor = Sensor(steps, revolutions)
        self.shaft = Shaft(start_turns, steps)
        self.cams = CamSwitch(breaks)
        self.offset = 0
        self.sync_counts: dict[int, int] = {}
        self._load(GROUPS[1], everything=True)
        self.node.add_read_callback(self._on_read)
        self.node.add_write_callback(self._on_write)
        self._computed: dict[int, Callable[[int], int | None]] = {
            POSITION: lambda sub: self.evaluate()[0],
            HIGH_PRECISION_POSITION: lambda sub: self.evaluate()[0],
            SPEED: lambda sub: self._speed() if sub == 1 else None,
            CAM_STATE: lambda sub: self.evaluate()[1] if sub == 1 else None,
            AREA_STATE: lambda sub: self.evaluate()[2] if sub == 1 else None,
            OPERATING_STATUS: lambda sub: self._int(OPERATING),
            OFFSET: lambda sub: self.offset - (1 << 32) if self.offset >= 1 << 31 else self.offset,
        }

    # -- object store ----------------------------------------------------------------------------
    def _factory_values(self, per_unit: dict[Key, object]) -> dict[Key, bytes]:
        """Values the EDS leaves open: the unit's own (identity, 6002h) and 0 / empty for the rest."""
        values = {}
        for key, var in self.variables.items():
            if key in per_unit:
                values[key] = var.encode_raw(per_unit[key])
            elif var.default is None and var.value is None:
                values[key] = var.encode_raw(0) if var.data_type in NUMBER_TYPES else b""
        return values

    def _int(self, index: int, sub: int = 0) -> int:
        var = self.variables[(index, sub)]
        return int(var.decode_raw(self.node.get_data(index, sub)))

    def _put(self, key: Key, data: bytes | None) -> None:
        store = self.node.data_store.setdefault(key[0], {})
        if data is None:
            store.pop(key[1], None)
        else:
            store[key[1]] = bytes(data)

    def _configurable(self, span: tuple[int, int]) -> list[Key]:
        return [k for k, v in self.variables.items()
                if v.writable and span[0] <= k[0] <= span[1] and k[0] not in (STORE, RESTORE)]

    def _load(self, span: tuple[int, int], everything: bool) -> None:
        """Power-on / reset: the values in ``span`` from the memory, else the factory's."""
        for key, var in self.variables.items():
            if not var.writable:
                if key in self.factory:
                    self._put(key, self.factory[key])
            elif span[0] <= key[0] <= span[1]:
                self._put(key, self.nvm.get(key, self.factory.get(key)))
        if everything:
            self.offset = self.nvm_offset or 0
            self.cams.forget()

    def _store(self, sub: int, data: bytes) -> None:
        if bytes(data) != SAVE or sub not in GROUPS:
            raise SdoAbortedError(ABORT_CANNOT_STORE)
        for key in self._configurable(GROUPS[sub]):
            self.nvm[key] = self.node.get_data(*key)
        if GROUPS[sub][0] <= OFFSET <= GROUPS[sub][1]:
            self.nvm_offset = self.offset

    def _restore(self, sub: int, data: bytes) -> None:
        if bytes(data) != LOAD or sub not in GROUPS:
            raise SdoAbortedError(ABORT_CANNOT_STORE)
        for key in self._configurable(GROUPS[sub]):
            if key[0] not in AUTO_SAVED:
                self.nvm.pop(key, None)
        if GROUPS[sub][0] <= OFFSET <= GROUPS[sub][1]:
            self.nvm_offset = None

    # -- the encoder function ------------------------------------------------------------------------
    def _units(self) -> Units:
        return Units(self._int(OPERATING), self._int(UNITS_PER_REV), self._int(TOTAL_RANGE),
                     self.sensor.revolutions > 1, self.breaks)

    def _cam_settings(self) -> CamSettings:
        return CamSettings(self._int(CAM_ENABLE, 1), self._int(CAM_POLARITY, 1),
                           tuple(self._int(CAM_LOW + n, 1) for n in range(CAMS)),
                           tuple(self._int(CAM_HIGH + n, 1) for n in range(CAMS)),
                           tuple(self._int(CAM_HYSTERESIS + n, 1) for n in range(CAMS)))

    def evaluate(self) -> tuple[int, int, int]:
        """(position, CAM state, work-area state) now; the cams see every position evaluated."""
        with self.lock:
            position = shown_position(self.shaft.turns(), self.sensor, self._units(), self.offset)
            cam = self.cams.update(position, self._cam_settings())
            area = area_state(position, self._int(AREA_LOW, 1), self._int(AREA_HIGH, 1))
            return position, cam, area

    def _speed(self) -> int:
        return speed_value(self.shaft.speed, self.sensor, self._units(), self._int(SPEED_SCALING, 1),
                           self._int(SPEED_SCALING, 2))

    def _preset(self, value: int) -> None:
        units = self._units()
        if value >= units.measuring_range(self.sensor):
            raise SdoAbortedError(ABORT_VALUE_TOO_HIGH)
        self.evaluate()  # the cams see the position before the jump
        self.offset = offset_for_preset(value, self.shaft.turns(), self.sensor, units)

    def _check(self, index: int, value: int) -> None:
        """Refuse what the texts rule out (the write is then not taken)."""
        if index == UNITS_PER_REV and not 1 <= value <= self.sensor.steps_per_rev:
            raise SdoAbortedError(ABORT_VALUE_TOO_LOW if value < 1 else ABORT_VALUE_TOO_HIGH)
        if index == TOTAL_RANGE and not 1 <= value <= MAX_TOTAL_RANGE:
            raise SdoAbortedError(ABORT_VALUE_TOO_LOW if value < 1 else ABORT_VALUE_TOO_HIGH)
        if CAM_LOW <= index < CAM_LOW + CAMS and value >= self._int(CAM_HIGH + index - CAM_LOW, 1):
            raise SdoAbortedError(ABORT_MAX_BELOW_MIN)  # WDGA M §7.5.4: low limit below its high limit

    # -- LocalNode callbacks ---------------------------------------------------------------------------
    def _on_read(self, index: int, subindex: int, od: ODVariable, **_: object) -> int | None:
        if index in (STORE, RESTORE) and subindex >= 1:
            return 1  # CiA 301: bit 0 = saves/restores on command
        computed = self._computed.get(index)
        if computed is None:
            return None
        with self.lock:
            return computed(subindex)

    def _on_write(self, index: int, subindex: int, od: ODVariable, data: bytes, **_: object) -> None:
        with self.lock:
            if index == STORE:
                self._store(subindex, data)
                return
            if index == RESTORE:
                self._restore(subindex, data)
                return
            value = int(od.decode_raw(data)) if od.data_type in NUMBER_TYPES else 0
            self._check(index, value)
            if index == PRESET:
                self._preset(value)
            self._put((index, subindex), data)  # in effect now (LocalNode stores it again after the callbacks)
            if index in AUTO_SAVED:
                self.nvm[(index, subindex)] = bytes(data)
            if 0x6000 <= index <= 0x6FFF:
                self.evaluate()

    def on_nmt(self, can_id: int, data: bytearray, timestamp: float) -> None:
        """After LocalNode's own NMT handling: reset node / communication reload, boot up, pre-operational."""
        if len(data) < 2 or data[1] not in (0, self.node.id) or data[0] not in (NMT_RESET_NODE,
                                                                                  NMT_RESET_COMMUNICATION):
            return
        with self.lock:
            everything = data[0] == NMT_RESET_NODE
            self._load(GROUPS[1] if everything else GROUPS[2], everything)
            self.sync_counts.clear()
        self.boot()

    def _restart_heartbeat(self) -> None:
        """A state change while the heartbeat runs: restart it with the new state byte. LocalNode would change the
        running task's data (``modify_data``), which python-can-remote's client task breaks on (it calls
        ``super(self)``: a TypeError in the bus's receive thread, after which the device answers nothing)."""
        nmt = self.node.nmt
        if nmt._send_task is not None:
            nmt.start_heartbeat(nmt._heartbeat_time_ms)

    def boot(self) -> None:
        """Boot-up message, then pre-operational (LocalNode starts the heartbeat from 1017h)."""
        self.node.nmt.stop_heartbeat()
        self.node.nmt.send_command(NMT_RESET_NODE)
        self.node.nmt.send_command(NMT_ENTER_PREOPERATIONAL)

    def on_sync(self, can_id: int, data: bytearray, timestamp: float) -> None:
        """Synchronous TPDOs (transmission types 1..240) in operational, with the mapped objects' values now."""
        if self.node.nmt.state != "OPERATIONAL":
            return
        with self.lock:
            frames = []
            for comm in TPDO_COMMUNICATION:
                if (comm, 1) not in self.variables:
                    continue
                cob_id, kind = self._int(comm, 1), self._int(comm, 2)
                if cob_id & COB_ID_INVALID or not 1 <= kind <= 240:
                    continue
                count = self.sync_counts.get(comm, 0) + 1
                self.sync_counts[comm] = 0 if count >= kind else count
                if count >= kind:
                    frames.append((cob_id & 0x7FF, self._mapped(comm + 0x200)))
        for cob_id, payload in frames:
            self.node.network.send_message(cob_id, payload)

    def _mapped(self, mapping: int) -> bytes:
        payload = b""
        for sub in range(1, self._int(mapping, 0) + 1):
            entry = self._int(mapping, sub)
            data = self.node.get_data(entry >> 16, entry >> 8 & 0xFF)
            size = (entry & 0xFF) // 8
            payload += data[:size].ljust(size, b"\x00")
        return payload[:8]

    # -- the shaft (driven through the link) ---------------------------------------------------------
    def turn_by(self, revolutions: float) -> None:
        with self.lock:
            self.evaluate()
            self.shaft.turn_by(revolutions)
            self.evaluate()

    def set_speed(self, revolutions_per_second: float) -> None:
        with self.lock:
            self.evaluate()
            self.shaft.set_speed(revolutions_per_second)
            self.evaluate()

    def angle(self) -> float:
        with self.lock:
            return self.shaft.turns()


def _variables(od: canopen.ObjectDictionary) -> list[ODVariable]:
    found = []
    for obj in od.values():
        found.extend([obj] if isinstance(obj, ODVariable) else obj.values())
    return found


class ShaftServer:
    """The device's end of the shaft link: one thread per connected drive."""

    def __init__(self, device: IndependentEncoder, address: tuple[str, int]) -> None:
        self.device = device
        self.listener = Listener(address, authkey=AUTHKEY)

    @property
    def address(self) -> tuple[str, int]:
        host, port = self.listener.address  # type: ignore[misc]
        return str(host), int(port)

    def start(self) -> None:
        threading.Thread(target=self._accept, name="shaft-link", daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                connection = self.listener.accept()
            except OSError:
                return
            threading.Thread(target=self._serve, args=(connection,), daemon=True).start()

    def _serve(self, connection: Connection) -> None:
        actions: dict[str, Callable[..., object]] = {"turn_by": self.device.turn_by,
                                                     "set_speed": self.device.set_speed, "angle": self.device.angle}
        while True:
            try:
                command, args = connection.recv()
            except (EOFError, OSError):
                return
            try:
                if command not in COMMANDS:
                    raise ValueError(f"unknown command {command!r}")
                connection.send((True, actions[command](*args)))
            except Exception as exc:
                connection.send((False, f"{type(exc).__name__}: {exc}"))


def export_eds(profile: str, folder: Path) -> Path:
    """The profile's EDS, written by the project's own command (this process imports nothing of it)."""
    path = folder / f"{profile}.eds"
    subprocess.run([sys.executable, "-m", "encoder_conformance", "profile", "to-eds", profile, "-o", str(path)],
                   check=True, capture_output=True, text=True)
    return path


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m tests.independent.encoder_device", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--channel", required=True, help="python-can-remote bus to join, ws://HOST:PORT/")
    parser.add_argument("--node-id", type=int, default=127, help="node-ID (default 127, the WDGA's delivery state)")
    parser.add_argument("--break", dest="breaks", action="append", choices=BREAKS, default=[],
                        help="a deliberate fault (repeatable)")
    parser.add_argument("--eds", type=Path, default=None,
                        help="object dictionary (default: encoder-conformance profile to-eds --profile's)")
    parser.add_argument("--profile", default=DEFAULT_PROFILE, help="profile whose EDS to export without --eds")
    parser.add_argument("--shaft-listen", default="127.0.0.1:0", help="address of the shaft link (port 0: any)")
    parser.add_argument("--serial", type=int, default=12345656,
                        help="1018h sub 4 / 650Bh sub 1 (default: the manual's label example, M §1.1)")
    parser.add_argument("--revision", type=lambda text: int(text, 0), default=0x03060208,
                        help="1018h sub 3 (default 0306 0208h: software 2.08, M §1.1)")
    parser.add_argument("--total-range", type=int, default=MAX_TOTAL_RANGE,
                        help="6002h of this unit (per unit in the manual; default 2^31, the largest it allows)")
    parser.add_argument("--revolutions", type=int, default=1 << 18,
                        help="revolutions the sensor distinguishes (default 2^18: 2^32 units at 16384 steps)")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="independent-encoder-") as folder:
        eds = args.eds or export_eds(args.profile, Path(folder))
        od = canopen.import_od(str(eds), args.node_id)
    per_unit: dict[Key, object] = {
        (0x1018, 3): args.revision, (0x1018, 4): args.serial, (SERIAL, 1): args.serial,
        (0x1009, 0): "AA", (0x100A, 0): "2.08", (0x6507, 0): 0x02080302, (TOTAL_RANGE, 0): args.total_range,
        (0x2500, 1): 25, (0x2500, 4): 25, (0x2500, 5): 25,
        (0x650A, 2): 0, (0x650A, 3): MAX_TOTAL_RANGE - 1,
    }
    start = (123_456 + 0.5) / 16384  # not at zero, in the middle of a step
    device = IndependentEncoder(od, args.node_id, frozenset(args.breaks),
                                {k: v for k, v in per_unit.items() if k in _keys(od)}, args.revolutions, start)
    shaft = ShaftServer(device, parse_address(args.shaft_listen))
    shaft.start()
    network = canopen.Network()
    network.connect(interface="remote", channel=args.channel)
    network.add_node(device.node)
    network.subscribe(0, device.on_nmt)
    network.subscribe(SYNC_COB_ID, device.on_sync)
    device.boot()
    info = {"shaft": format_address(shaft.address), "node_id": args.node_id, "breaks": args.breaks}
    print("READY " + json.dumps(info), flush=True)
    wait_for_sigterm()
    network.disconnect()
    sys.stdout.flush()
    os._exit(0)  # the websocket threads would hold the interpreter's shutdown


def _keys(od: canopen.ObjectDictionary) -> set[Key]:
    return {(v.index, v.subindex) for v in _variables(od)}


if __name__ == "__main__":
    sys.exit(main())
