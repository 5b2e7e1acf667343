"""TPDO engine: SYNC-driven (types 0..240), event-driven (254/255) with event timer and change check.

Reads its configuration from 1800h+n (communication) and 1A00h+n (mapping) whenever the node
enters operational or a PDO parameter is written. A FixedTpdoLayout (quirk ``fixed_tpdo_mapping``)
replaces mapping objects and transmission types the device does not have, and adds RTR answers.
SendRepeatCounters (quirk ``pdo_send_repeat_counters``) add sends per change and a SYNC send limit.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from .faults import FaultSet
from .pdo_layout import FixedTpdoLayout
from .scheduler import DeadlineScheduler, JobHandle
from .send_repeat import SendRepeatCounters, within_sync_limit

CHANGE_POLL_S = 0.005


@dataclass
class TpdoConfig:
    number: int  # 1-based
    cob_id: int
    valid: bool
    transmission_type: int
    inhibit_100us: int
    event_timer_ms: float  # effective timer period (0: no timer)
    mapping: list[tuple[int, int, int]]  # (index, sub, bits)
    sync_every: int = 0  # sent on every n-th SYNC (0: not SYNC-counted)
    on_change: bool = False  # sent when the payload changes
    acyclic_sync: bool = False  # type 0: sent on a SYNC after the payload changed
    rtr: bool = False  # answers a remote frame on its COB-ID
    sync_count: int = 0
    sends_per_change: int = 1  # frames per detected change (send-repeat counter)
    repeats_left: int = 0  # frames of the last change still to send, one per change poll
    sync_limit: int = 0  # SYNC-driven frames in all until the payload changes (0: no limit)
    sync_sent: int = 0
    last_payload: bytes | None = None
    last_sent: float = field(default=-1e9)


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
        faults: FaultSet | None = None,
        repeat: SendRepeatCounters | None = None,
    ) -> None:
        self._scheduler = scheduler
        self._repeat = repeat
        self._read = read
        self._mapped_bytes = mapped_bytes
        self._send = send
        self._count = count
        self._timer_zero_disables_255 = timer_zero_disables_255
        self._layout = layout
        self._faults = faults or FaultSet()
        self._configs: list[TpdoConfig] = []
        self._jobs: list[JobHandle] = []
        self.running = False

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
                cob_id=cob_id & 0x1FFFFFFF if cob_id & 0x20000000 else cob_id & 0x7FF,
                valid=not cob_id & 0x80000000,
                transmission_type=self._read(comm, 2) or 0,
                inhibit_100us=self._read(comm, 3) or 0,
                event_timer_ms=self._read(comm, 5) or 0,
                mapping=self._mapping(comm),
            )
            self._cia_semantics(config)
            if self._layout is not None:
                self._layout_semantics(comm, config, self._layout)
            if config.sync_every and self._faults.active("sync_tpdo_every_sync"):
                config.sync_every = 1
            if self._repeat is not None and not self._faults.active("send_repeat_counter_ignored"):
                self._repeat.configure(comm, config, self._read)
            configs.append(config)
        return configs

    def _mapping(self, comm: int) -> list[tuple[int, int, int]]:
        if self._layout is not None and comm in self._layout.mapping:
            return list(self._layout.mapping[comm])
        mapping = comm + 0x200
        entries = []
        for sub in range(1, (self._read(mapping, 0) or 0) + 1):
            word = self._read(mapping, sub) or 0
            entries.append((word >> 16, (word >> 8) & 0xFF, word & 0xFF))
        return entries

    def _cia_semantics(self, config: TpdoConfig) -> None:
        """CiA 301 transmission types: 1..240 every n-th SYNC, 254/255 on change and event timer."""
        kind = config.transmission_type
        config.sync_every = kind if 1 <= kind <= 240 else 0
        config.acyclic_sync = kind == 0
        event_driven = kind in (254, 255)
        disables = self._timer_zero_disables_255 and not self._faults.active("type_255_timer_0_sends")
        if kind == 255 and config.event_timer_ms == 0 and disables:
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
            if config.event_timer_ms > 0:
                period = config.event_timer_ms / 1000
                if self._faults.active("event_timer_slow_20pct"):
                    period *= 1.2
                self._jobs.append(
                    self._scheduler.call_later(period, lambda c=config: self._transmit(c), period)
                )
        if any(c.on_change for c in self._configs):
            for config in self._configs:
                config.last_payload = self._payload(config)
            self._jobs.append(self._scheduler.call_later(CHANGE_POLL_S, self._poll_changes, CHANGE_POLL_S))

    def stop(self) -> None:
        self.running = False
        for job in self._jobs:
            job.cancel()
        self._jobs.clear()

    def reload(self) -> None:
        if self.running:
            self.start()

    def on_sync(self) -> None:
        if not self.running:
            return
        for config in self._configs:
            if config.sync_every:
                config.sync_count += 1
                if config.sync_count >= config.sync_every:
                    config.sync_count = 0
                    if within_sync_limit(config, self._payload(config)):
                        self._transmit(config)
            elif config.acyclic_sync and self._payload(config) != config.last_payload:
                self._transmit(config)

    def on_rtr(self, cob_id: int) -> None:
        """A remote frame: TPDOs that answer RTR on this COB-ID send their current payload."""
        if not self.running:
            return
        for config in self._configs:
            if config.rtr and config.cob_id == cob_id:
                self._transmit(config, inhibit=False)

    def _poll_changes(self) -> None:
        for config in self._configs:
            if config.on_change and self._payload(config) != config.last_payload:
                self._transmit(config)
                config.repeats_left = config.sends_per_change - 1
            elif config.repeats_left > 0:
                config.repeats_left -= 1
                self._transmit(config)

    def _payload(self, config: TpdoConfig) -> bytes:
        data = b"".join(self._mapped_bytes(i, s, bits) for i, s, bits in config.mapping)
        return data[:8]

    def _transmit(self, config: TpdoConfig, inhibit: bool = True) -> None:
        if not self.running:
            return
        now = time.monotonic()
        if inhibit and config.inhibit_100us and now - config.last_sent < config.inhibit_100us / 10000:
            return
        payload = self._payload(config)
        config.last_payload = payload
        config.last_sent = now
        self._send(config.cob_id, payload)
