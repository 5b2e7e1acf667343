"""``encoder-conformance restore --from SNAPSHOT``: finish a restore a run could not (crash, power loss, Ctrl-C).

Connects to the device the snapshot was taken from (the serial number must match), resets it,
writes back and stores what differs from the stored snapshot, then the values that were in use.
An encoder's preset objects are never written back as values (a snapshot of an older run may hold
them): its reference point is given back by presetting, where the snapshot recorded it. A device with LSS that an
LSS test had moved (the snapshot lists the node-IDs it gave it) or that does not answer at its node-ID is looked
for and put back first (``dut/lss/lss_custody.py``): at those node-IDs, by its LSS address, unconfigured, after reset
communication, after a power cycle where power commands are given.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from encoder_conformance.config.bus import BusConfig
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.bench.power import BenchPower, PowerSwitchError, ShellPowerSwitch
from encoder_conformance.dut.bench.power_on import power_cycler
from encoder_conformance.dut.bench.reference_point import preset_keys
from encoder_conformance.dut.custody.custody import Custody, RestoreRecord
from encoder_conformance.dut.custody.snapshot import Snapshot
from encoder_conformance.dut.link import connection
from encoder_conformance.dut.link.device import wake_if_silent
from encoder_conformance.dut.link.frames import FrameLog, Mark
from encoder_conformance.dut.lss.lss_custody import Changes, LssCustody
from encoder_conformance.dut.lss.lss_master import LssAddress, LssMaster
from encoder_conformance.dut.sdo.identity import read_identity
from encoder_conformance.dut.store.store_watch import StoreWatch
from encoder_conformance.errors import BusSetupError, DutLostError
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.schema import DeviceProfile


@dataclass(frozen=True)
class RestoreRequest:
    snapshot_path: Path
    bus: BusConfig
    node_id: int | None
    timeout_s: float
    force: bool
    power_on_command: str | None = None
    power_off_command: str | None = None


def restore_from_snapshot(request: RestoreRequest) -> int:
    """Run the restore; print what it did; the exit code (RunExit)."""
    try:
        snapshot = Snapshot.load(request.snapshot_path)
    except ValueError as exc:
        return _fail(str(exc), RunExit.USAGE_ERROR)
    loaded = load_profile(snapshot.profile_id)
    if loaded.sha256 != snapshot.profile_sha256:
        print(f"note: profile {snapshot.profile_id} changed since the snapshot; restoring the snapshot's values")
    _leave_out_presets(snapshot, loaded.profile)
    if request.power_on_command:  # a crash between power off and on leaves the device switched off
        try:
            ShellPowerSwitch("true", request.power_on_command).on()
        except PowerSwitchError as exc:
            return _fail(str(exc), RunExit.COULD_NOT_TEST)
    frames = FrameLog()
    try:
        network = connection.connect(request.bus.kwargs, request.bus.describe(), frames)
    except BusSetupError as exc:
        return _fail(str(exc), RunExit.COULD_NOT_TEST)
    try:
        # a device with LSS belongs at the snapshot's node-ID: --node-id says where else it may be now
        node_id = snapshot.node_id if loaded.profile.capabilities.lss else request.node_id or snapshot.node_id
        dut = DeviceUnderTest(network, frames, loaded.profile, node_id)
        moved = bool(snapshot.lss_node_ids) and loaded.profile.capabilities.lss
        problem = None if moved else _wrong_device(dut, snapshot, request.force)
        if moved or (problem and problem.startswith("no answer") and loaded.profile.capabilities.lss):
            recovered = _lss_recover(dut, snapshot, request)
            if recovered is not None:
                return _fail(f"{problem + '; ' if problem else ''}{recovered}", RunExit.NOT_RESTORED)
            print(f"node-ID {node_id} given back by LSS")
            problem = _wrong_device(dut, snapshot, request.force)
        if problem:
            return _fail(problem, RunExit.COULD_NOT_TEST)
        watch = StoreWatch(loaded.profile, node_id)
        frames.add_listener(watch)
        custody = Custody(dut, None, watch)
        custody.snapshot = snapshot
        record = custody.give_back(request.timeout_s, check_stored=True)
    finally:
        connection.disconnect(network)
    _print(record)
    return RunExit.PASSED if record.ok else RunExit.NOT_RESTORED


def _leave_out_presets(snapshot: Snapshot, profile: DeviceProfile) -> None:
    """A snapshot of an older run holds the preset objects as values: writing one back would preset again."""
    presets = set(preset_keys(profile))
    left_out = [e for e in snapshot.entries if e.key in presets]
    snapshot.entries = [e for e in snapshot.entries if e.key not in presets]
    for entry in left_out:
        print(f"note: {entry.label} not written back: writing a preset value moves the reference point"
              + ("" if snapshot.reference_in_use else " (this snapshot did not record the reference point)"))


def _wrong_device(dut: DeviceUnderTest, snapshot: Snapshot, force: bool) -> str | None:
    """None if the node answers and is the snapshot's unit (same serial number); else why not."""
    try:
        with dut.in_custody():
            wake_if_silent(dut)  # a device just switched on may wait for bus traffic
            if not (dut.responds() or dut.responds() or dut.nmt.reset_and_reach()):
                return f"no answer from node {dut.node_id}: check --node-id, the bit rate, termination and power"
            identity = read_identity(dut).as_report()
    except DutLostError as exc:
        return f"the device could not be reached: {exc}"
    serial, expected = identity.get("serial number (1018h.4)"), snapshot.serial
    if expected not in (None, "-") and serial != expected and not force:
        return (f"node {dut.node_id} is not the device of the snapshot: serial {serial}, the snapshot has "
                f"{expected}. Connect that device, or give --force to write this snapshot onto another unit")
    return None


def _lss_address(snapshot: Snapshot) -> LssAddress | None:
    """The LSS address (1018h sub 1..4) the snapshot recorded, or None where a part is missing."""
    keys = ("vendor-id (1018h.1)", "product code (1018h.2)", "revision (1018h.3)", "serial number (1018h.4)")
    try:
        parts = [int(snapshot.identity.get(key, "-").split()[0], 0) for key in keys]
    except ValueError:
        return None
    return LssAddress(*parts)


def _lss_recover(dut: DeviceUnderTest, snapshot: Snapshot, request: RestoreRequest) -> str | None:
    """A run stopped while an LSS test had moved the device (or made it unconfigured): look for it wherever it may
    be and give it its node-ID back; None, or one line saying where it is and what to run."""
    address = _lss_address(snapshot)
    if address is None:
        return "the snapshot does not give the LSS address (1018h sub 1..4) needed to select the device"
    master = LssMaster(lambda cob_id, data: dut.network.send_message(cob_id, data), dut.frames,
                       dut.profile.timing.lss_response_ms / 1000)
    power: Callable[[], Mark] | None = None
    if request.power_off_command and request.power_on_command:
        switch = BenchPower(ShellPowerSwitch(request.power_off_command, request.power_on_command))
        power = power_cycler(dut, switch)
    candidates = frozenset(snapshot.lss_node_ids) | ({request.node_id} if request.node_id else set())
    hint = (f"encoder-conformance restore --from {request.snapshot_path} again"
            + ("" if power else " (or give --power-off-cmd CMD --power-on-cmd CMD)"))
    custody = LssCustody(dut, master, address, snapshot.node_id, None, power, candidates, hint)
    # what a test may have stored is unknown here: store the node-ID as found again where the device can
    with dut.in_custody():
        problem = custody.put_back(Changes(node_id=True, bit_timing=False, stored=True))
    if problem is None:
        snapshot.lss_node_ids.clear()
        snapshot.save(request.snapshot_path)
    return problem


def _print(record: RestoreRecord) -> None:
    print(f"found {len(record.stored_changed)} stored value(s) and {len(record.left_changed)} value(s) in use "
          f"that differ from the snapshot")
    for line in record.written:
        print(f"  wrote {line}")
    for command in record.store_commands:
        print(f"  stored with {command}")
    if record.memory:
        print(f"MEMORY NOT AS FOUND: {record.memory}", file=sys.stderr)
    if record.ok and not record.memory:
        print(f"device restored as found: every value checked ({record.seconds:.2f} s)")
    for failure in record.failures:
        print(f"NOT RESTORED: {failure}", file=sys.stderr)


def _fail(text: str, code: int) -> int:
    print(f"restore: {text}", file=sys.stderr)
    return code
