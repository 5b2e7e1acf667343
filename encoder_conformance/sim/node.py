"""One simulated CANopen node playing a device profile, including its documented quirks.

Frames arrive through ``on_frame`` (from the host's receive thread); everything timed runs on
the shared DeadlineScheduler; outgoing frames go through the ``send`` function the host gives.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from pathlib import Path

import can

from ..profile.model import DeviceProfile, resolve_node_id_expression
from ..profile.od_builder import initial_value
from . import access as codes
from .access import NodeObjectAccess
from .emcy import EmcyProducer
from .encoder import EncoderFunction
from .faults import FaultSet
from .forced_bits import force_bits
from .guarding import GuardingHeartbeatExclusion
from .nmt import TARGET, NmtCommand, NmtState, pdo_allowed, sdo_allowed, sync_allowed
from .nvm import Key, NonVolatileMemory
from .object_store import ObjectStore
from .pdo_layout import FixedTpdoLayout
from .scheduler import DeadlineScheduler, JobHandle
from .sdo_server import SdoAbort, SdoServer
from .send_repeat import SendRepeatCounters
from .shaft import Shaft
from .store_commands import StoreCommands
from .tpdo import TpdoEngine

log = logging.getLogger(__name__)

#: fault that makes the node ignore each state-changing NMT command
IGNORE_FAULT = {
    NmtCommand.START: "ignore_start",
    NmtCommand.STOP: "ignore_stop",
    NmtCommand.ENTER_PRE_OPERATIONAL: "ignore_enter_preop",
}

Send = Callable[[int, bytes, bool], None]


class SimulatedNode:
    """The twin of one device: NMT, heartbeat, SDO server, TPDOs, EMCY, store/restore, shaft."""

    def __init__(
        self,
        profile: DeviceProfile,
        scheduler: DeadlineScheduler,
        send: Send,
        node_id: int | None = None,
        nvm_path: Path | None = None,
        faults: FaultSet | None = None,
    ) -> None:
        self.profile = profile
        self.scheduler = scheduler
        self._send_raw = send
        self.faults = faults or FaultSet()
        self.configured_node_id = node_id if node_id is not None else profile.bus.node_id
        self.node_id = self.configured_node_id
        self.nvm = NonVolatileMemory(nvm_path)
        self._preconfigure_node_id()
        self.store = ObjectStore(profile, self.nvm, self._node_id_at_power_on())
        self.access = NodeObjectAccess(self)
        self.sdo = SdoServer(self.access)
        self.store_commands = StoreCommands(self)
        self.shaft = Shaft()
        self.encoder = EncoderFunction(profile, self.store, self.shaft, scheduler)
        self.lock = threading.RLock()
        self.state: NmtState | None = None  # None = powered off
        self.hidden_indices = {max(profile.objects)} if self.faults.active("missing_object") else set()
        self._awaiting_traffic = False
        self._heartbeat_job: JobHandle | None = None
        self._boot_job: JobHandle | None = None
        self._heartbeat_count = 0
        self.emcy = EmcyProducer(
            self.store,
            self.send,
            allowed=lambda: self.state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL),
            node_id=lambda: self.node_id,
            without_generic_bit=self.quirk_params("error_register_without_generic_bit") is not None,
            cob_offset=1 if self.faults.active("emcy_wrong_cob_id") else 0,
        )
        exclusion = self.quirk_params("guarding_heartbeat_exclusive")
        self.guarding = None if exclusion is None else GuardingHeartbeatExclusion.from_params(exclusion, self.faults)
        self.tpdo = TpdoEngine(
            scheduler,
            read=self._read_int,
            mapped_bytes=self._mapped_bytes,
            send=lambda cob_id, data: self.send(cob_id, data),
            count=profile.capabilities.tpdos,
            timer_zero_disables_255=self.quirk_params("transmission_type_255_timer_0_disables") is not None,
            layout=self._fixed_tpdo_layout(),
            faults=self.faults,
            repeat=self._send_repeat_counters(),
        )

    # -- helpers -------------------------------------------------------------------------
    def _fixed_tpdo_layout(self) -> FixedTpdoLayout | None:
        params = self.quirk_params("fixed_tpdo_mapping")
        return None if params is None else FixedTpdoLayout.from_params(params)

    def _send_repeat_counters(self) -> SendRepeatCounters | None:
        params = self.quirk_params("pdo_send_repeat_counters")
        return None if params is None else SendRepeatCounters.from_params(params)

    def _force_bits(self, event: str) -> None:
        """Quirk bits_forced_at_init at power_on / nmt_81h / nmt_82h (not stored, only current)."""
        if not self.faults.active("forced_bits_not_applied"):
            force_bits(self.quirk_params("bits_forced_at_init"), self.store, event)

    def quirk_params(self, effect: str) -> dict | None:
        """The params of the profile's quirk with ``effect``, or None if it has none."""
        found = self.profile.quirk_with_effect(effect)
        return None if found is None else found[1].params

    def _read_int(self, index: int, sub: int) -> int | None:
        key = (index, sub)
        if not self.store.has(key):
            return None
        value = self.store.get(key)
        return value if isinstance(value, int) else None

    def send(self, cob_id: int, data: bytes, extended: bool = False) -> None:
        if self.state is None:
            return
        self._send_raw(cob_id, data, extended)

    def _preconfigure_node_id(self) -> None:
        """A twin started with --node-id behaves as if configured before delivery."""
        quirk = self.quirk_params("node_id_object")
        if quirk and self.configured_node_id != self.profile.bus.node_id:
            key = (int(quirk["index"]), int(quirk.get("subindex", 0)))
            if key not in self.nvm:
                self.nvm.put_many({key: self.configured_node_id})

    def _node_id_at_power_on(self) -> int:
        quirk = self.quirk_params("node_id_object")
        if quirk:
            stored = self.nvm.get((int(quirk["index"]), int(quirk.get("subindex", 0))))
            if isinstance(stored, int) and 1 <= stored <= 127:
                return stored
        return self.configured_node_id

    def _apply_value_faults(self) -> None:
        """wrong_default: every reload leaves writable UNSIGNED values one above their default."""
        if not self.faults.active("wrong_default"):
            return
        for key, entry in self.store.entries.items():
            value = self.store.get(key)
            default = resolve_node_id_expression(self.default_value(key), self.node_id)  # type: ignore[arg-type]
            if (
                entry.writable
                and isinstance(value, int)
                and value == default
                and entry.type.startswith("UNSIGNED")
                and key[0] not in (0x1010, 0x1011)
            ):
                self.store.set(key, value + 1)

    # -- power and boot ------------------------------------------------------------------
    def power_on(self) -> None:
        """Apply power: reload everything from NVM, then boot (or wait for bus traffic)."""
        with self.lock:
            self._load_everything()
            self.state = NmtState.INITIALISING
            self._awaiting_traffic = self.quirk_params("silent_until_bus_traffic") is not None
            if not self._awaiting_traffic:
                self._schedule_boot(power_on=True)

    def _load_everything(self) -> None:
        """What a (re)start loads: node-id, every value from NVM or default, no error history."""
        self.node_id = self._node_id_at_power_on()
        self.store.reload(lambda index: True, self.node_id)
        self.encoder.reload(self.nvm)
        self._apply_value_faults()
        self._force_bits("power_on")
        self.emcy.clear_history()

    def power_off(self) -> None:
        with self.lock:
            self._stop_services()
            self.sdo.reset()
            self.encoder.thaw()
            self.state = None

    def reboot(self, delay_s: float) -> None:
        """The device restarts by itself: silent while it initialises, boot-up after ``delay_s``."""
        self._stop_services()
        self.sdo.reset()
        self.state = NmtState.INITIALISING
        self._load_everything()
        self._boot_job = self.scheduler.call_later(delay_s, lambda: self._finish_boot(power_on=True))

    def power_cycle(self) -> None:
        self.power_off()
        self.power_on()

    def _stop_services(self) -> None:
        for job in (self._heartbeat_job, self._boot_job):
            if job is not None:
                job.cancel()
        self._heartbeat_job = self._boot_job = None
        self.tpdo.stop()

    def _schedule_boot(self, power_on: bool) -> None:
        delay = self.profile.simulator.bootup_delay_ms / 1000
        self._boot_job = self.scheduler.call_later(delay, lambda: self._finish_boot(power_on))

    def _finish_boot(self, power_on: bool) -> None:
        with self.lock:
            if self.state is not NmtState.INITIALISING:
                return
            silent = not power_on and self.faults.active("no_bootup_after_reset")
            if not silent:
                self.send(0x700 + self.node_id, b"\x00")
            self._enter(NmtState.PRE_OPERATIONAL)
            self._restart_heartbeat()
            if self._starts_itself():
                self._enter(NmtState.OPERATIONAL)

    def _starts_itself(self) -> bool:
        """Quirk nmt_autostart_object: the object holds the value that means 'enter operational by itself'."""
        params = self.quirk_params("nmt_autostart_object")
        if params is None or self.faults.active("autostart_ignored"):
            return False
        value = self._read_int(int(params["index"]), int(params.get("subindex", 0)))
        return value == int(params["operational_value"])

    def _reset(self, node: bool) -> None:
        """NMT reset node (everything) or reset communication (1000h-1FFFh) and boot again."""
        with self.lock:
            self._stop_services()
            self.sdo.reset()
            self.state = NmtState.INITIALISING
            self.node_id = self._node_id_at_power_on()
            if node and not self.faults.active("reset_node_keeps_values"):
                self.store.reload(lambda index: True, self.node_id)
                self.encoder.reload(self.nvm)
            else:
                self.store.reload(lambda index: 0x1000 <= index <= 0x1FFF, self.node_id)
            self._apply_value_faults()
            self._force_bits("nmt_81h" if node else "nmt_82h")
            self._schedule_boot(power_on=False)

    # -- heartbeat -----------------------------------------------------------------------
    def _heartbeat_period_s(self) -> float:
        value = self._read_int(0x1017, 0) or 0
        period = value / 1000
        return period * 1.2 if self.faults.active("heartbeat_slow_20pct") else period

    def _restart_heartbeat(self) -> None:
        if self._heartbeat_job is not None:
            self._heartbeat_job.cancel()
            self._heartbeat_job = None
        period = self._heartbeat_period_s()
        if period <= 0 or not self.profile.capabilities.heartbeat_producer:
            return
        start = time.monotonic()
        self._heartbeat_count = 0
        if self.faults.active("heartbeat_jitter"):
            self._heartbeat_job = self.scheduler.call_at(start + period, lambda: self._jittered(start, period))
        else:
            self._heartbeat_job = self.scheduler.call_at(start + period, self._send_heartbeat, period)

    def _jittered(self, start: float, period: float) -> None:
        self._send_heartbeat()
        self._heartbeat_count += 1
        k = self._heartbeat_count + 1
        due = start + k * period + (0.3 * period if k % 4 == 0 else 0.0)
        self._heartbeat_job = self.scheduler.call_at(due, lambda: self._jittered(start, period))

    def _send_heartbeat(self) -> None:
        state = self.state
        if state is None or state is NmtState.INITIALISING:
            return
        value = int(state)
        if state is NmtState.PRE_OPERATIONAL and self.faults.active("wrong_heartbeat_state"):
            value = int(NmtState.OPERATIONAL)
        payload = bytes([value, 0]) if self.faults.active("heartbeat_wrong_dlc") else bytes([value])
        self.send(0x700 + self.node_id, payload)

    # -- frame dispatch ------------------------------------------------------------------
    def on_frame(self, msg: can.Message) -> None:
        with self.lock:
            if self.state is None or msg.is_error_frame:
                return
            if self._awaiting_traffic:
                self._awaiting_traffic = False  # bit rate detected from this frame
                self._schedule_boot(power_on=True)
                return
            if self.state is NmtState.INITIALISING:
                return
            can_id = msg.arbitration_id
            if can_id == 0 and not msg.is_extended_id:
                self._on_nmt(bytes(msg.data))
            elif can_id == 0x600 + self.node_id and not msg.is_remote_frame:
                self._on_sdo(bytes(msg.data))
            elif self._is_sync(msg) and sync_allowed(self.state):
                self.tpdo.on_sync()
            elif msg.is_remote_frame and not msg.is_extended_id:
                self.tpdo.on_rtr(can_id)  # answered only by TPDOs that allow RTR, in operational

    def _is_sync(self, msg: can.Message) -> bool:
        cob = self._read_int(0x1005, 0)
        cob = 0x80 if cob is None else cob & 0x7FF
        return msg.arbitration_id == cob and not msg.is_extended_id and not msg.is_remote_frame

    def _on_nmt(self, data: bytes) -> None:
        if len(data) != 2:
            return
        command, target = data
        if target == 0 and self.faults.active("ignore_broadcast"):
            return
        if target not in (0, self.node_id) and not self.faults.active("respond_to_other_node"):
            return
        try:
            cmd = NmtCommand(command)
        except ValueError:
            return
        if cmd is NmtCommand.RESET_NODE:
            self._reset(node=True)
        elif cmd is NmtCommand.RESET_COMMUNICATION:
            if not self.faults.active("reset_comm_keeps_state"):
                self._reset(node=False)
        elif not self.faults.active(IGNORE_FAULT[cmd]):
            self._enter(TARGET[cmd])

    def _enter(self, state: NmtState) -> None:
        previous, self.state = self.state, state
        if state is previous:
            return
        if pdo_allowed(state) or self.faults.active("pdo_outside_operational"):
            self.tpdo.start()
        else:
            self.tpdo.stop()
        if state is NmtState.STOPPED:
            self.sdo.reset()  # a transfer in progress cannot continue in stopped

    def _on_sdo(self, data: bytes) -> None:
        if self.faults.active("no_sdo_response"):
            return
        if not sdo_allowed(self.state) and not self.faults.active("sdo_in_stopped"):
            return
        if data and data[0] >> 5 in (5, 6, 7) and self.faults.active("ignore_unknown_command"):
            return
        response = self.sdo.handle(data)
        if response is not None and response[0] == 0x80 and self.faults.active("abort_without_multiplexer"):
            response = response[:1] + bytes(3) + response[4:]  # as canopen's own client does (issue #377)
        if response is not None:
            self.send(0x580 + self.node_id, response)

    # -- values seen through SDO and PDO ---------------------------------------------------
    def position(self) -> int:
        return self.encoder.position()

    def current_value(self, key: Key, channel: str = "sdo") -> int | str | bytes:
        """Computed entries come from the encoder; the rest from the store (with identity faults)."""
        computed = self.encoder.value(key, channel)
        if computed is not None:
            return computed
        reads_back = self.quirk_params("store_object_reads_back")
        if reads_back is not None and key[0] in (0x1010, 0x1011) and key[1] >= 1:
            return int(reads_back.get("value", 0))
        value = self.store.get(key)
        return self._identity_fault(key, value)

    def _identity_fault(self, key: Key, value: int | str | bytes) -> int | str | bytes:
        faults = self.faults
        if isinstance(value, int):
            if (key == (0x1018, 1) and faults.active("wrong_vendor_id")) or (key == (0x1018, 2) and faults.active(
                "wrong_product_code"
            )):
                return (value + 1) & 0xFFFFFFFF
            if key == (0x1018, 3) and faults.active("wrong_revision"):
                return 0xFFFFFFFF
            if key == (0x1018, 0) and faults.active("wrong_identity_size"):
                return value + 1
            if key == (0x1018, 4) and faults.active("serial_mismatch"):
                return (value ^ 0x1) & 0xFFFFFFFF
            if key == (0x1000, 0) and faults.active("wrong_device_type"):
                return (value & 0xFFFF0000) | ((value + 1) & 0xFFFF)
        if key == (0x1008, 0) and faults.active("wrong_device_name"):
            return f"X{value}"
        return value

    def encode_current(self, key: Key, channel: str = "sdo") -> bytes:
        value = self.current_value(key, channel)
        if isinstance(value, bytes):
            return value
        if isinstance(value, str):
            return value.encode("latin-1")
        size = self.store.size(key)
        if isinstance(value, int) and size and not self.store.entries[key].type.startswith("REAL"):
            return (value & ((1 << (8 * size)) - 1)).to_bytes(size, "little")  # two's complement
        return self.store.variable(key).encode_raw(value)

    def _mapped_bytes(self, index: int, sub: int, bits: int) -> bytes:
        key = (index, sub)
        if not self.store.has(key):
            return bytes(bits // 8)
        return self.encode_current(key, "tpdo").ljust(bits // 8, b"\x00")[: bits // 8]

    # -- writes: gates and effects ---------------------------------------------------------
    def quirk_write_gate(self, key: Key, value: int | str | bytes) -> None:
        """Profile quirks that refuse a write in the current situation."""
        if self.guarding is not None:
            self.guarding.gate(key, value, self._read_int)
        gate = self.quirk_params("writes_preop_only")
        if gate and key[0] in gate.get("objects", []) and self.state is not NmtState.PRE_OPERATIONAL:
            raise SdoAbort(int(gate.get("abort_code", self.access.codes["wrong_state"])))
        gate = self.quirk_params("writes_need_scaling_bit")
        if gate and key[0] in gate.get("objects", []) and not (self._read_int(0x6000, 0) or 0) & 0x04:
            raise SdoAbort(int(gate.get("abort_code", self.access.codes["wrong_state"])))

    def apply_write(self, key: Key, value: int | str | bytes) -> None:
        index, sub = key
        if self.store_commands.on_write(key, value):
            return
        if index == 0x1003 and sub == 0:
            if value != 0:
                raise SdoAbort(codes.VALUE_INVALID)
            self.emcy.clear_history()
            return
        self.encoder.on_write(key, value)
        self.store.set(key, value)
        self.store_commands.after_write(key, value)
        if self.guarding is not None:
            self.guarding.after_write(key, value, self.store.set)
        if index == 0x1017:
            if value == 0 and self.faults.active("heartbeat_ignores_zero"):
                return
            self._restart_heartbeat()
        elif 0x1800 <= index <= 0x1BFF or index in self.tpdo.reload_indices:
            self.tpdo.reload()

    # -- control API (used by the control server and in-process tests) ----------------------
    def default_value(self, key: Key) -> object:
        return initial_value(self.profile, key[0], key[1], self.store.entries[key], self.node_id)

    def raise_emcy(self, code: int, register_bits: int, info: bytes = b"") -> None:
        with self.lock:
            self.emcy.raise_error(code, register_bits, info)

    def describe(self) -> dict[str, object]:
        return {
            "profile": self.profile.id,
            "node_id": self.node_id,
            "state": None if self.state is None else self.state.name,
            "faults": sorted(self.faults.names),
            "position": self.position(),
        }

