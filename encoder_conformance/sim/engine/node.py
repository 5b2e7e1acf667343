"""One simulated CANopen node playing a device profile: the behaviours, wired together.

The node does not decide anything itself. It builds its behaviours (NMT slave, heartbeat, SDO
channel and access rules, store commands, EMCY, TPDO engine, encoder function and the quirks'
own behaviours), each with only the collaborators it uses, lets each register for the objects and
events it cares about (``sim/engine/hooks.py``), and dispatches received frames. Faults are put in when a
behaviour is built (``assemble``, ``sim/engine/faults.py``). Frames arrive through ``on_frame`` (from the
host, one at a time); everything timed runs on the shared DeadlineScheduler; outgoing frames
go through the ``send`` function the host gives.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Protocol, TypeVar

import can

from encoder_conformance.cia import cia301, cia305  # by module: sim/engine/node.py stays within 400 lines
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.datatypes import as_signed
from encoder_conformance.profile.od_builder import initial_value
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine import sdo_fuzz_faults, sdo_short_frames, tpdo_sync_cycle  # noqa: F401  (register the SDO fuzzing faults, the short-frame variants, a TPDO variant)
from encoder_conformance.sim.engine.access import ObjectAccess, situation_codes
from encoder_conformance.sim.engine.autostart import Autostart
from encoder_conformance.sim.engine.cam_gate import CamLowLimitGate
from encoder_conformance.sim.engine.emcy import EmcyProducer
from encoder_conformance.sim.engine.encoder import EncoderFunction
from encoder_conformance.sim.engine.faults import FaultSet, assemble
from encoder_conformance.sim.engine.forced_bits import ForcedBits
from encoder_conformance.sim.engine.guarding import GuardingHeartbeatExclusion
from encoder_conformance.sim.engine.heartbeat import HeartbeatProducer
from encoder_conformance.sim.engine.heartbeat_consumer import HeartbeatConsumer
from encoder_conformance.sim.engine.hooks import NodeHooks, ReloadEvent
from encoder_conformance.sim.engine.lss_behaviour import LssBehaviour
from encoder_conformance.sim.engine.lss_configuration import usable_node_id
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nmt_error_behaviour import CommErrorBehaviour, StartUpFailure
from encoder_conformance.sim.engine.nmt_slave import NmtSlave
from encoder_conformance.sim.engine.nvm import Key, NonVolatileMemory
from encoder_conformance.sim.engine.object_store import ObjectStore
from encoder_conformance.sim.engine.pdo_cob_id import PdoCobIdRules
from encoder_conformance.sim.engine.pdo_layout import FixedTpdoLayout
from encoder_conformance.sim.engine.pdo_mapping import MappingRules
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler
from encoder_conformance.sim.engine.sdo_block import BlockEngine
from encoder_conformance.sim.engine.sdo_channel import SdoChannel
from encoder_conformance.sim.engine.sdo_server import SdoServer
from encoder_conformance.sim.engine.send_repeat import SendRepeatCounters
from encoder_conformance.sim.engine.shaft import Shaft
from encoder_conformance.sim.engine.sim_log import EventLog
from encoder_conformance.sim.engine.store_commands import EncoderMemory, StoreCommands
from encoder_conformance.sim.engine.store_variants import ReadsBack
from encoder_conformance.sim.engine.sync_counter import SyncCounterRules
from encoder_conformance.sim.engine.sync_objects import SyncCobIdRules, SyncConsumer, SyncLengthCheck
from encoder_conformance.sim.engine.sync_producer import SyncProducer
from encoder_conformance.sim.engine.sync_timeout import SyncTimeoutMonitor
from encoder_conformance.sim.engine.timer_link import CyclicTimerLink
from encoder_conformance.sim.engine.tpdo import TpdoEngine
from encoder_conformance.sim.engine.values import ObjectValues
from encoder_conformance.sim.engine.write_gates import preop_only, scaling_bit_needed
from encoder_conformance.sim.engine.zeroing import Zeroing

Send = Callable[[int, bytes, bool], None]
P = TypeVar("P", bound=fx.EffectParams)
T = TypeVar("T")


class Behaviour(Protocol):
    def register(self, hooks: NodeHooks) -> None: ...


class SimulatedNode:
    """The twin of one device."""

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
        self.faults = faults = faults or FaultSet()
        self.configured_node_id = node_id if node_id is not None else profile.bus.node_id
        self.nvm = NonVolatileMemory(nvm_path)
        self._preconfigure_node_id()
        self.lock = threading.RLock()
        self.hooks = hooks = NodeHooks()
        self.lss: LssBehaviour | None = None
        self.store = assemble(ObjectStore, faults)(profile, self.nvm, self._node_id_for(None))
        self.nmt = assemble(NmtSlave, faults)(
            hooks, self.store, scheduler, self._send, self._node_id_for,
            boot_delay_s=profile.simulator.bootup_delay_ms / 1000,
            silent_until_bus_traffic=profile.has_effect(fx.SilentUntilBusTraffic),
            lock=self.lock,
        )
        self.shaft = Shaft()
        self.encoder = assemble(EncoderFunction, faults)(profile, self.store, self.shaft, scheduler)
        self.values = assemble(ObjectValues, faults)(self.store, hooks)
        codes = situation_codes(profile)
        self.access = assemble(ObjectAccess, faults)(profile, self.store, hooks, self.values.encode, codes)
        block = assemble(BlockEngine, faults) if profile.capabilities.block_sdo else None
        self.sdo = assemble(SdoServer, faults)(self.access, block, later=self._sdo_later,
                                               timeout_s=profile.timing.sdo_transfer_timeout_ms / 1000)
        self.sdo_channel = assemble(SdoChannel, faults)(self.sdo, self._send, lambda: self.state, lambda: self.node_id)
        self.heartbeat = assemble(HeartbeatProducer, faults)(
            scheduler, self._send, self.read_int, lambda: self.state, lambda: self.node_id,
            enabled=profile.capabilities.heartbeat_producer,
        )
        self.emcy = assemble(EmcyProducer, faults)(
            self.store, scheduler, self._send,
            allowed=lambda: self.state in self._emcy_states(),
            node_id=lambda: self.node_id,
            without_generic_bit=profile.has_effect(fx.ErrorRegisterWithoutGenericBit),
            history_keeps_first=profile.has_effect(fx.ErrorHistoryKeepsFirst),
        )
        self.sync_consumer = assemble(SyncConsumer, faults)(self.read_int)
        self.tpdo = assemble(TpdoEngine, faults)(
            scheduler,
            read=self.read_int,
            mapped_bytes=self.values.mapped_bytes,
            send=self._send,
            count=profile.capabilities.tpdos,
            timer_zero_disables_255=profile.has_effect(fx.TransmissionType255Timer0Disables),
            layout=self._built(fx.FixedTpdoMapping, FixedTpdoLayout.from_params),
            repeat=self._built(fx.PdoSendRepeatCounters, SendRepeatCounters.from_params),
            response_max_s=profile.timing.pdo_response_max_ms / 1000,
        )
        self.error_behaviour = assemble(CommErrorBehaviour, faults)(scheduler, self.read_int, self.nmt, self.lock)
        events = EventLog(lambda: self.node_id)
        self.nvm.listeners.append(events.nvm_changed)
        for behaviour in (events, *self._behaviours(codes)):
            behaviour.register(hooks)

    def _behaviours(self, codes: dict[str, int]) -> list[Behaviour]:
        """Every behaviour of this node in the order its hooks run (writes: gates, commands, reactions)."""
        faults, wrong_state = self.faults, codes["wrong_state"]
        store_commands = assemble(StoreCommands, faults)(
            self.profile, self.store, EncoderMemory(self.encoder.persist, self.encoder.forget),
            self.reboot, self.default_value, codes,
        )
        optional: list[Behaviour | None] = [
            self._built(fx.GuardingHeartbeatExclusive, lambda p: assemble(GuardingHeartbeatExclusion, faults)
                        .from_params(p, self.read_int, self.store.set)),
            *(preop_only(q.params, lambda: self.state, wrong_state, faults)
              for q in self.profile.quirks_with(fx.WritesPreopOnly)),
            self._built(fx.WritesNeedScalingBit, lambda p: scaling_bit_needed(p, self.read_int, wrong_state)),
            self._built(fx.CamLowBelowHigh, self._cam_low_limit_gate),
            assemble(PdoCobIdRules, faults)(self.read_int, lambda: self.state),
            assemble(SyncCounterRules, faults)(self.read_int, wrong_state),
            assemble(SyncCobIdRules, faults)(self.profile.params_of(fx.SyncCobIdAnyCanId),
                                             can_produce=self.profile.capabilities.sync_producer is True),
            assemble(SyncProducer, faults)(self.scheduler, self.read_int, self.send, lambda: self.state, self.lock),
            assemble(SyncTimeoutMonitor, faults)(self.scheduler, self.read_int, self.nmt, self._raise_error, self.lock),
            self.error_behaviour,
            assemble(StartUpFailure, faults)(self._raise_error, self.nmt),
            assemble(MappingRules, faults)(self.profile, self.read_int, codes),
            store_commands,
            self.emcy,
            *self._emcy_triggers(),
            # the encoder function only where the profile is an encoder (a drive keeps its 6004h/6030h/6500h)
            _EncoderBehaviour(self.encoder, self.nvm) if self.profile.capabilities.encoder else None,
            self._built(fx.ZeroingObject, lambda p: assemble(Zeroing, faults)(
                p, lambda: self.encoder.apply_preset(0), self._preset_is_zero)),
            self._built(fx.BitsForcedAtInit, lambda p: assemble(ForcedBits, faults)(p, self.store)),
            self.heartbeat,
            self._built(fx.CyclicTimerRelationUnstated, lambda p: assemble(CyclicTimerLink, faults)(p, self.store)),
            self._built(fx.NmtAutostartObject, lambda p: assemble(Autostart, faults)(p, self.read_int,
                                                                                        self.nmt.enter)),
            self.tpdo,
            self._built(fx.StoreObjectReadsBack, ReadsBack),
            self.sdo_channel,
            self._lss(),
        ]
        return [b for b in optional if b is not None]

    def _emcy_states(self) -> tuple[NmtState, ...]:
        """Where an EMCY may go out: pre-operational and operational (CiA 301 §7.3.2.2), stopped too per quirk."""
        usual = (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)
        return (*usual, NmtState.STOPPED) if self.profile.has_effect(fx.EmcyInStopped) else usual

    def _emcy_triggers(self) -> list[Behaviour]:
        """The errors the bus can cause: a SYNC of the wrong length (where 1019h exists), a heartbeat-consumer
        time-out (where 1016h exists)."""
        triggers: list[Behaviour] = []
        if self.profile.entry(cia301.SYNC_COUNTER_OVERFLOW, 0) is not None:
            triggers.append(assemble(SyncLengthCheck, self.faults)(self.read_int, self._raise_error))
        entries = self.profile.capabilities.heartbeat_consumer_entries
        if entries and self.profile.entry(cia301.HEARTBEAT_CONSUMER, 1) is not None:
            quirk = self.profile.params_of(fx.HeartbeatConsumerEmcy)
            code = quirk.code if quirk else cia301.EmcyCode.HEARTBEAT
            triggers.append(assemble(HeartbeatConsumer, self.faults)(self.scheduler, self.read_int, entries,
                                                                     self._raise_error, code))
        return triggers

    def _raise_error(self, code: int, register_bits: int) -> None:
        with self.lock:  # also from the scheduler's thread
            self.emcy.raise_error(code, register_bits)
            self.error_behaviour.after_error(register_bits)

    def _cam_low_limit_gate(self, params: fx.CamLowBelowHigh) -> CamLowLimitGate:
        cam = self.profile.capabilities.cam
        return assemble(CamLowLimitGate, self.faults)(
            params, self.encoder.read_int, lambda key, value: as_signed(self.store.entries[key].type, value),
            cam.cams_per_channel if cam else 0,
        )

    def _preset_is_zero(self) -> bool:
        return not self.encoder.read_int(self.encoder.objects.preset)

    def _lss(self) -> LssBehaviour | None:
        """The LSS slave, where the profile declares LSS services (capabilities.lss)."""
        if not self.profile.capabilities.lss:
            return None

        def address() -> tuple[int, int, int, int]:  # 1018h as the device shows it (identity faults included)
            parts = [self.current_value((0x1018, sub)) if self.store.has((0x1018, sub)) else 0 for sub in range(1, 5)]
            first, second, third, fourth = (p if isinstance(p, int) else 0 for p in parts)
            return first, second, third, fourth

        self.lss = assemble(LssBehaviour, self.faults)(self.profile, self.nvm, self.store, self.nmt, address,
                                                       self._send, self.faults)
        return self.lss

    # -- helpers -------------------------------------------------------------------------
    def _built(self, effect: type[P], build: Callable[[P], T]) -> T | None:
        """``build(params)`` of the profile's quirk with that effect, or None if it has none."""
        params = self.profile.params_of(effect)
        return None if params is None else build(params)

    def read_int(self, index: int, sub: int) -> int | None:
        key = (index, sub)
        if not self.store.has(key):
            return None
        value = self.store.get(key)
        return value if isinstance(value, int) else None

    def _send(self, cob_id: int, data: bytes) -> None:
        self.send(cob_id, data)

    def send(self, cob_id: int, data: bytes, extended: bool = False) -> None:
        if self.state is None or (self.lss is not None and not self.lss.may_send()):
            return
        self._send_raw(cob_id, data, extended)

    def _preconfigure_node_id(self) -> None:
        """A twin started with --node-id behaves as if configured before delivery."""
        quirk = self.profile.params_of(fx.NodeIdObject)
        if quirk and self.configured_node_id != self.profile.bus.node_id and quirk.key not in self.nvm:
            self.nvm.put_many({quirk.key: self.configured_node_id})

    def _node_id_for(self, event: ReloadEvent | None) -> int:
        """The node-ID a (re)start takes (None: construction): what LSS applied or stored, else the
        manufacturer node-ID object's stored value, else the node-ID the twin was started with."""
        if event is not None and self.lss is not None:
            by_lss = self.lss.node_id_after(event)
            if by_lss is not None:
                return by_lss
        quirk = self.profile.params_of(fx.NodeIdObject)
        if quirk:
            stored = usable_node_id(self.nvm.get(quirk.key))
            if stored is not None:
                return stored
        return self.configured_node_id

    # -- state, power and boot (the NMT slave's) -------------------------------------------
    @property
    def state(self) -> NmtState | None:
        return self.nmt.state

    @property
    def node_id(self) -> int:
        return self.nmt.node_id

    def power_on(self, at_once: bool = False) -> None:
        """Apply power: reload everything from NVM, then boot (or wait for bus traffic); ``at_once``: without
        the boot delay (switched on before anyone looked)."""
        with self.lock:
            self.nmt.power_on(at_once)

    def power_off(self) -> None:
        with self.lock:
            self.nmt.power_off()

    def power_cycle(self) -> None:
        self.power_off()
        self.power_on()

    def reboot(self, delay_s: float) -> None:
        """The device restarts by itself: silent while it initialises, boot-up after ``delay_s``."""
        self.nmt.reboot(delay_s)

    def _sdo_later(self, delay_s: float, produce: Callable[[], list[bytes]]) -> None:
        """The SDO server's own time-outs: after ``delay_s`` the frames ``produce`` returns go out (none where the
        transfer has moved on)."""
        def run() -> None:
            with self.lock:
                self.sdo_channel.send_frames(produce())

        self.scheduler.call_at(time.monotonic() + delay_s, run)

    # -- frame dispatch ------------------------------------------------------------------
    def on_frame(self, msg: can.Message) -> None:
        with self.lock:
            if self.state is None or msg.is_error_frame or (self.lss is not None and not self.lss.hears()):
                return
            if self.nmt.bus_traffic_seen():
                return  # bit rate detected from this frame
            can_id = msg.arbitration_id
            if can_id == cia305.MASTER_COB_ID and not msg.is_extended_id and not msg.is_remote_frame:
                if self.state is not NmtState.INITIALISING or self.nmt.waiting_for_node_id:
                    for listener in self.hooks.lss:
                        listener(bytes(msg.data))
                return
            if self.state is NmtState.INITIALISING and not (
                    can_id == cia301.NMT_COB_ID and self.lss is not None
                    and self.lss.obeys_nmt_while_unconfigured(bytes(msg.data))):
                return
            if can_id == cia301.NMT_COB_ID and not msg.is_extended_id:
                self.nmt.on_command(bytes(msg.data))
            elif can_id == cia301.SDO_REQUEST_BASE + self.node_id and not msg.is_remote_frame:
                self.sdo_channel.on_request(bytes(msg.data))
            elif self.sync_consumer.is_sync(msg):
                # every state: each listener knows when a SYNC acts on it (the TPDO engine only in operational,
                # CiA 301 §7.3.2.2), so that a fault of the listener alone can break that
                counter = msg.data[0] if msg.dlc >= 1 else None
                for sync_listener in self.hooks.sync:
                    sync_listener(counter)
                for length_listener in self.hooks.sync_length:
                    length_listener(msg.dlc)
            elif can_id in cia301.HEARTBEAT_IDS and msg.dlc == 1 and not (msg.is_extended_id or msg.is_remote_frame):
                for heartbeat_listener in self.hooks.heartbeat:
                    heartbeat_listener(can_id - cia301.HEARTBEAT_BASE)
            elif msg.is_remote_frame and not msg.is_extended_id:
                for rtr_listener in self.hooks.remote_frame:  # answered only by TPDOs that allow RTR
                    rtr_listener(can_id)

    # -- control API (used by the control server and in-process tests) ----------------------
    def position(self) -> int:
        return self.encoder.position()

    def current_value(self, key: Key, channel: str = "sdo") -> int | float | str | bytes:
        return self.values.current(key, channel)

    def encode_current(self, key: Key, channel: str = "sdo") -> bytes:
        return self.values.encode(key, channel)

    def default_value(self, key: Key) -> object:
        return initial_value(self.profile, key[0], key[1], self.store.entries[key], self.node_id)

    def raise_emcy(self, code: int, register_bits: int, info: bytes = b"") -> None:
        with self.lock:
            self.emcy.raise_error(code, register_bits, info)

    def clear_emcy(self) -> None:
        """The cause of the errors went away: error register 0 and the error-reset EMCY."""
        with self.lock:
            self.emcy.clear()

    def describe(self) -> dict[str, object]:
        return {
            "profile": self.profile.id,
            "node_id": self.node_id,
            "state": None if self.state is None else self.state.name,
            "faults": sorted(self.faults.names),
            "position": self.position(),
        }


class _EncoderBehaviour:
    """Registers the encoder function: computed values, freeze/preset on writes, reload of its NVM part."""

    def __init__(self, encoder: EncoderFunction, nvm: NonVolatileMemory) -> None:
        self._encoder = encoder
        self._nvm = nvm

    def register(self, hooks: NodeHooks) -> None:
        hooks.sources.append(self._encoder.value)
        hooks.before_set.append(self._encoder.on_write)
        hooks.reload.append(lambda event: self._encoder.reload(self._nvm) if event.everything else None)
        hooks.powered_off.append(self._encoder.thaw)
