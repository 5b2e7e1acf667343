"""TPDO engine: SYNC-driven (types 0..240, SYNC start value), RTR-only (252/253), event-driven (254/255) with
event timer and change check.

Reads its configuration from 1800h+n (communication) and 1A00h+n (mapping) whenever the node
enters operational or a PDO parameter is written. A FixedTpdoLayout (quirk ``fixed_tpdo_mapping``)
replaces mapping objects and transmission types the device does not have, and adds RTR answers.
SendRepeatCounters (quirk ``pdo_send_repeat_counters``) add sends per change and a SYNC send limit.
A behaviour: it registers for NMT state changes, SYNC, remote frames and writes to PDO parameters;
faults that break it are the small classes at the bottom. The module is over 400 lines because those 19
faults (one per PDO check, ~140 lines) sit next to the engine they break, as everywhere in sim/; the engine
itself is under 300 lines.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial

from encoder_conformance.cia.cia301 import (
    COB_ID_FRAME_29_BIT,
    COB_ID_INVALID,
    COB_ID_NO_RTR,
    PDO_MAPPING_OFFSET,
    RTR_EVENT,
    RTR_SYNCHRONOUS,
    SYNC_COUNTER_OVERFLOW,
)
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nmt import NmtState, pdo_allowed
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.pdo_layout import FixedTpdoLayout
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler, JobHandle
from encoder_conformance.sim.engine.send_repeat import SendRepeatCounters, within_sync_limit
from encoder_conformance.sim.engine.tpdo_config import TpdoConfig

CHANGE_POLL_S = 0.005


class TpdoEngine:
    """Decides when each TPDO is sent; the node supplies values and the transmit function."""

    def __init__(
        self,
        scheduler: DeadlineScheduler,
        read: Callable[[int, int], int | None],
        mapped_bytes: Callable[[int, int, int], bytes],
        send: Callable[[int, bytes], None],
        count: int,
        timer_zero_disables_255: bool = False,
        layout: FixedTpdoLayout | None = None,
        repeat: SendRepeatCounters | None = None,
        response_max_s: float = 0.01,
    ) -> None:
        self._scheduler = scheduler
        self._response_max_s = response_max_s  # the profile's pdo_response_max_ms (what a late fault exceeds)
        self._repeat = repeat
        self._read = read
        self._mapped_bytes = mapped_bytes
        self._send = send
        self._count = count
        self._timer_zero_disables_255 = timer_zero_disables_255
        self._layout = layout
        self._configs: list[TpdoConfig] = []
        self._jobs: list[JobHandle] = []
        self.running = False

    def register(self, hooks: NodeHooks) -> None:
        hooks.state.append(self.on_state)
        hooks.halted.append(self.stop)
        hooks.on_written(self.on_parameter_written, [*range(0x1800, 0x1C00), *self.reload_indices])
        hooks.sync.append(self.on_sync)
        hooks.remote_frame.append(self.on_rtr)

    def sends_in(self, state: NmtState) -> bool:
        return pdo_allowed(state)

    def on_state(self, state: NmtState) -> None:
        if self.sends_in(state):
            self.start()
        else:
            self.stop()

    def on_parameter_written(self, key: Key, value: Value) -> None:
        self.reload()

    @property
    def reload_indices(self) -> frozenset[int]:
        """Objects outside 1800h..1BFFh whose write changes the TPDO configuration."""
        timers = self._layout.timer_objects if self._layout else frozenset()
        return timers | (self._repeat.counter_objects if self._repeat else frozenset())

    def _load(self) -> list[TpdoConfig]:
        configs: list[TpdoConfig] = []
        for comm in range(0x1800, 0x1A00):  # not always consecutive (POSITAL uses 1800h and 1802h)
            if len(configs) == self._count:
                break
            cob_id = self._read(comm, 1)
            if cob_id is None:
                continue
            config = TpdoConfig(
                number=comm - 0x1800 + 1,
                cob_id=cob_id & 0x1FFFFFFF if cob_id & COB_ID_FRAME_29_BIT else cob_id & 0x7FF,
                valid=self.is_valid(cob_id),
                transmission_type=self._read(comm, 2) or 0,
                inhibit_100us=self._read(comm, 3) or 0,
                event_timer_ms=self._read(comm, 5) or 0,
                mapping=self._mapping(comm),
                rtr_allowed=not cob_id & COB_ID_NO_RTR,
                sync_start=self.sync_start_value(comm),
            )
            self._cia_semantics(config)
            if self._layout is not None:
                self._layout_semantics(comm, config, self._layout)
            config.sync_every = self.sync_divisor(config.sync_every)
            if self._repeat is not None:
                self.apply_send_repeat(comm, config, self._repeat)
            configs.append(config)
        return configs

    def is_valid(self, cob_id: int) -> bool:
        """Sub 1 bit 31 clear: the PDO exists (CiA 301 §7.5.2.37)."""
        return not cob_id & COB_ID_INVALID

    def sync_start_value(self, comm: int) -> int:
        """Sub 6, where 1019h > 0 makes the SYNC carry a counter (CiA 301 §7.5.2.37): the counter value of
        the first SYNC counted; 0 where there is none."""
        if not self._read(SYNC_COUNTER_OVERFLOW, 0):
            return 0
        return self._read(comm, 6) or 0

    def sync_divisor(self, every: int) -> int:
        """Sent on every n-th SYNC: n as configured (0: not SYNC-counted)."""
        return every

    def apply_send_repeat(self, comm: int, config: TpdoConfig, repeat: SendRepeatCounters) -> None:
        repeat.configure(comm, config, self._read)

    def timer_zero_disables_255(self) -> bool:
        return self._timer_zero_disables_255

    def timer_period_s(self, config: TpdoConfig) -> float:
        return config.event_timer_ms / 1000

    def _mapping(self, comm: int) -> list[tuple[int, int, int]]:
        if self._layout is not None and comm in self._layout.mapping:
            return list(self._layout.mapping[comm])
        mapping = comm + PDO_MAPPING_OFFSET
        entries = []
        for sub in range(1, (self._read(mapping, 0) or 0) + 1):
            word = self._read(mapping, sub) or 0
            entries.append((word >> 16, (word >> 8) & 0xFF, word & 0xFF))
        return entries

    def _cia_semantics(self, config: TpdoConfig) -> None:
        """CiA 301 transmission types: 0 on a SYNC after a change, 1..240 every n-th SYNC, 252 sampled at SYNC and
        sent on RTR, 253 sent on RTR (both only where sub 1 bit 30 allows RTR), 254/255 on change and event timer."""
        kind = config.transmission_type
        config.sync_every = kind if 1 <= kind <= 240 else 0
        config.acyclic_sync = kind == 0
        config.rtr = kind in (RTR_SYNCHRONOUS, RTR_EVENT) and config.rtr_allowed
        config.sampled_at_sync = kind == RTR_SYNCHRONOUS
        event_driven = kind in (254, 255)
        if kind == 255 and config.event_timer_ms == 0 and self.timer_zero_disables_255():
            event_driven = False
        config.on_change = event_driven
        if not event_driven:
            config.event_timer_ms = 0

    def _layout_semantics(self, comm: int, config: TpdoConfig, layout: FixedTpdoLayout) -> None:
        """Fixed layout: period from a manufacturer object, SYNC counter 1..255, RTR answers."""
        if comm in layout.cyclic:
            period_object, unit_ms = layout.cyclic[comm]
            config.event_timer_ms = (self._read(period_object, 0) or 0) * unit_ms
            config.sync_every, config.on_change, config.acyclic_sync = 0, False, False
        if comm in layout.sync_counter:
            config.sync_every = self._read(comm, layout.sync_counter[comm]) or 0
            config.event_timer_ms, config.on_change, config.acyclic_sync = 0, False, False
        config.rtr = comm in layout.polled

    def start(self) -> None:
        """Enter operational: (re)load the configuration and arm timers."""
        self.stop()
        self._configs = [c for c in self._load() if c.valid and c.mapping]
        self.running = True
        for config in self._configs:
            config.last_payload = self._payload(config)  # type 0 and the change check: changes from now on
            config.waiting_for_start = config.sync_start > 0
        for config in self._configs:
            if config.event_timer_ms > 0:
                period = self.timer_period_s(config)
                self._jobs.append(
                    self._scheduler.call_later(period, partial(self._transmit, config), period)
                )
        if any(c.on_change for c in self._configs):
            self._jobs.append(self._scheduler.call_later(CHANGE_POLL_S, self._poll_changes, CHANGE_POLL_S))

    def stop(self) -> None:
        self.running = False
        for job in self._jobs:
            job.cancel()
        self._jobs.clear()

    def reload(self) -> None:
        if self.running:
            self.start()

    def on_sync(self, counter: int | None = None) -> None:
        """A SYNC (``counter``: its counter byte, None without one)."""
        if not self.running:
            return
        for config in self._configs:
            if config.sampled_at_sync:
                config.sample = self._payload(config)
            if config.sync_every:
                if config.waiting_for_start:  # the SYNC whose counter is the start value is the first one counted
                    if counter != config.sync_start:
                        continue
                    config.waiting_for_start = False
                    config.sync_count = config.sync_every - 1
                config.sync_count += 1
                if config.sync_count >= config.sync_every:
                    config.sync_count = 0
                    if within_sync_limit(config, self._payload(config)):
                        self.answer_sync(config)
            elif config.acyclic_sync and self.acyclic_due(config):
                self._transmit(config)

    def acyclic_due(self, config: TpdoConfig) -> bool:
        """Type 0: the mapped value changed since the TPDO was last sent."""
        return self._payload(config) != config.last_payload

    def answers_rtr(self, config: TpdoConfig) -> bool:
        return config.rtr

    def on_rtr(self, cob_id: int) -> None:
        """A remote frame: TPDOs that answer RTR on this COB-ID send their current payload."""
        if not self.running:
            return
        for config in self._configs:
            if self.answers_rtr(config) and config.cob_id == cob_id:
                self._transmit(config, inhibit=False, payload=config.sample if config.sampled_at_sync else None)

    def _poll_changes(self) -> None:
        for config in self._configs:
            if config.on_change and self.change_seen(config):
                self._transmit(config)
                config.repeats_left = config.sends_per_change - 1
            elif config.repeats_left > 0:
                config.repeats_left -= 1
                self._transmit(config)

    def change_seen(self, config: TpdoConfig) -> bool:
        """Event-driven types: the mapped value differs from the one last sent."""
        return self._payload(config) != config.last_payload

    def answer_sync(self, config: TpdoConfig) -> None:
        """A SYNC-counted TPDO whose SYNC came: sent at once."""
        self._transmit(config)

    def _payload(self, config: TpdoConfig) -> bytes:
        data = b"".join(self._mapped_bytes(i, s, bits) for i, s, bits in config.mapping)
        return data[:8]

    def _transmit(self, config: TpdoConfig, inhibit: bool = True, payload: bytes | None = None) -> None:
        """Send now, or, inside the inhibit time, as ``inside_inhibit`` decides (``payload``: values sampled
        earlier, e.g. at the SYNC of a type 252)."""
        if not self.running:
            return
        now = time.monotonic()
        wait = self.inhibit_s(config) - (now - config.last_sent)
        if inhibit and wait > 0:
            self.inside_inhibit(config, wait)
            return
        payload = self._payload(config) if payload is None else payload
        config.last_payload = payload
        self._send(config.cob_id, payload)
        config.last_sent = time.monotonic()  # after the frame is stamped: the next one is an inhibit time later

    def inhibit_s(self, config: TpdoConfig) -> float:
        """The minimum time between two transmissions (CiA 301 §7.5.2.37: sub 3 in 100 us, types 254/255 only)."""
        return config.inhibit_100us / 10000 if config.transmission_type in (254, 255) else 0.0

    def inside_inhibit(self, config: TpdoConfig, wait: float) -> None:
        """A transmission inside the inhibit time is delayed, never dropped (CiA 301 §7.5.2.37): one send when the
        time is over, carrying the values of that moment."""
        if not config.delayed:
            config.delayed = True
            self._jobs.append(self._scheduler.call_later(wait, lambda: self._send_delayed(config)))

    def _send_delayed(self, config: TpdoConfig) -> None:
        config.delayed = False
        self._transmit(config)


@breaks(TpdoEngine, "sync_tpdo_every_sync")
class SendsOnEverySync(TpdoEngine):
    def sync_divisor(self, every: int) -> int:
        return 1 if every else 0


@breaks(TpdoEngine, "send_repeat_counter_ignored")
class SendRepeatIgnored(TpdoEngine):
    def apply_send_repeat(self, comm: int, config: TpdoConfig, repeat: SendRepeatCounters) -> None:
        return


@breaks(TpdoEngine, "type_255_timer_0_sends")
class Type255Timer0Sends(TpdoEngine):
    def timer_zero_disables_255(self) -> bool:
        return False


@breaks(TpdoEngine, "event_timer_slow_20pct")
class SlowEventTimer(TpdoEngine):
    def timer_period_s(self, config: TpdoConfig) -> float:
        return super().timer_period_s(config) * 1.2


@breaks(TpdoEngine, "pdo_outside_operational")
class SendsOutsideOperational(TpdoEngine):
    def sends_in(self, state: NmtState) -> bool:
        return True


#: how long after leaving operational ``tpdo_late_after_leaving_operational`` sends
LATE_TPDO_S = 0.04


@breaks(TpdoEngine, "tpdo_late_after_leaving_operational")
class TpdoLateAfterLeavingOperational(TpdoEngine):
    """Each TPDO that was sent in operational is sent once more LATE_TPDO_S after leaving it (a queue flushed late)."""

    def on_state(self, state: NmtState) -> None:
        leaving = self.running and not self.sends_in(state)
        sent = [c for c in self._configs if c.valid and c.last_sent > 0] if leaving else []
        super().on_state(state)
        for config in sent:
            self._scheduler.call_later(LATE_TPDO_S, partial(self._send_late, config))

    def _send_late(self, config: TpdoConfig) -> None:
        self._send(config.cob_id, self._payload(config))


@breaks(TpdoEngine, "tpdo_not_resumed_after_stopped")
class NotResumedAfterStopped(TpdoEngine):
    """Once stopped, the TPDOs stay silent (also in operational) until a reset halts the node."""

    was_stopped = False

    def register(self, hooks: NodeHooks) -> None:
        super().register(hooks)
        hooks.halted.append(self._forget_stop)

    def _forget_stop(self) -> None:
        self.was_stopped = False

    def on_state(self, state: NmtState) -> None:
        self.was_stopped = self.was_stopped or state is NmtState.STOPPED
        if self.was_stopped:
            self.stop()
        else:
            super().on_state(state)


@breaks(TpdoEngine, "event_timer_outside_operational")
class EventTimerOutsideOperational(TpdoEngine):
    left_operational = False

    def on_state(self, state: NmtState) -> None:
        self.left_operational = not self.sends_in(state)
        if not self.left_operational:
            self.start()  # leaving operational cancels nothing: the event timers keep firing

    def on_sync(self, counter: int | None = None) -> None:
        if not self.left_operational:  # SYNC-driven TPDOs do stop
            super().on_sync(counter)


@breaks(TpdoEngine, "sync_tpdo_off_by_one")
class SendsOnEveryNPlusOneSync(TpdoEngine):
    def sync_divisor(self, every: int) -> int:
        return every + 1 if every else 0


@breaks(TpdoEngine, "cob_id_valid_bit_ignored")
class ValidBitIgnored(TpdoEngine):
    def is_valid(self, cob_id: int) -> bool:
        return True


@breaks(TpdoEngine, "type_0_sends_every_sync")
class Type0SendsEverySync(TpdoEngine):
    def acyclic_due(self, config: TpdoConfig) -> bool:
        return True


@breaks(TpdoEngine, "sync_start_value_ignored")
class SyncStartValueIgnored(TpdoEngine):
    def sync_start_value(self, comm: int) -> int:
        return 0


@breaks(TpdoEngine, "rtr_ignored")
class RtrIgnored(TpdoEngine):
    def answers_rtr(self, config: TpdoConfig) -> bool:
        return False


@breaks(TpdoEngine, "rtr_bit_30_ignored")
class RtrOnEveryTpdo(TpdoEngine):
    def answers_rtr(self, config: TpdoConfig) -> bool:
        return True


@breaks(TpdoEngine, "change_of_state_ignored")
class ChangeOfStateIgnored(TpdoEngine):
    def change_seen(self, config: TpdoConfig) -> bool:
        return False


@breaks(TpdoEngine, "tpdo_on_sync_outside_operational")
class SyncTpdoOutsideOperational(TpdoEngine):
    def on_state(self, state: NmtState) -> None:
        was_running = self.running
        super().on_state(state)
        if was_running and not self.sends_in(state):
            self.running = True  # timers and the change check stopped; SYNC (and RTR) still make TPDOs


@breaks(TpdoEngine, "change_tpdo_outside_operational")
class ChangeTpdoOutsideOperational(TpdoEngine):
    outside = False

    def on_state(self, state: NmtState) -> None:
        was_running = self.running
        super().on_state(state)
        self.outside = was_running and not self.sends_in(state)
        if self.outside and any(c.on_change for c in self._configs):
            self.running = True  # the change check goes on; SYNC-driven TPDOs and timers stopped
            self._jobs.append(self._scheduler.call_later(CHANGE_POLL_S, self._poll_changes, CHANGE_POLL_S))

    def on_sync(self, counter: int | None = None) -> None:
        if not self.outside:
            super().on_sync(counter)



@breaks(TpdoEngine, "payload_not_matching_mapping")
class PayloadNotMatchingMapping(TpdoEngine):
    """The mapped objects go out in reverse order; a single entry one byte late."""

    def _payload(self, config: TpdoConfig) -> bytes:
        if len(config.mapping) > 1:
            reverse = TpdoConfig(**{**config.__dict__, "mapping": config.mapping[::-1]})
            return super()._payload(reverse)
        return (b"\x00" + super()._payload(config))[:8]



@breaks(TpdoEngine, "inhibit_ignored")
class InhibitIgnored(TpdoEngine):
    def inhibit_s(self, config: TpdoConfig) -> float:
        return 0.0  # every change goes out at once, however close to the previous frame


@breaks(TpdoEngine, "inhibit_drops_events")
class InhibitDropsEvents(TpdoEngine):
    def inside_inhibit(self, config: TpdoConfig, wait: float) -> None:
        config.last_payload = self._payload(config)  # the change is taken and thrown away: nothing follows it


@breaks(TpdoEngine, "sync_tpdo_late")
class SyncTpdoLate(TpdoEngine):
    def answer_sync(self, config: TpdoConfig) -> None:
        delay = 3 * self._response_max_s
        self._jobs.append(self._scheduler.call_later(delay, lambda: self._transmit(config)))
