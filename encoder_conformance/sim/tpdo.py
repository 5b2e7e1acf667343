"""TPDO engine: SYNC-driven (types 0..240), event-driven (254/255) with event timer and change check.

Reads its configuration from 1800h+n (communication) and 1A00h+n (mapping) whenever the node
enters operational or a PDO parameter is written.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from .scheduler import DeadlineScheduler, JobHandle

CHANGE_POLL_S = 0.005


@dataclass
class TpdoConfig:
    number: int  # 1-based
    cob_id: int
    valid: bool
    transmission_type: int
    inhibit_100us: int
    event_timer_ms: int
    mapping: list[tuple[int, int, int]]  # (index, sub, bits)
    sync_count: int = 0
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
    ) -> None:
        self._scheduler = scheduler
        self._read = read
        self._mapped_bytes = mapped_bytes
        self._send = send
        self._count = count
        self._timer_zero_disables_255 = timer_zero_disables_255
        self._configs: list[TpdoConfig] = []
        self._jobs: list[JobHandle] = []
        self.running = False

    def _load(self) -> list[TpdoConfig]:
        configs: list[TpdoConfig] = []
        for comm in range(0x1800, 0x1A00):  # not always consecutive (POSITAL uses 1800h and 1802h)
            if len(configs) == self._count:
                break
            mapping = comm + 0x200
            cob_id = self._read(comm, 1)
            if cob_id is None:
                continue
            n = comm - 0x1800
            entries = []
            for sub in range(1, (self._read(mapping, 0) or 0) + 1):
                word = self._read(mapping, sub) or 0
                entries.append((word >> 16, (word >> 8) & 0xFF, word & 0xFF))
            configs.append(
                TpdoConfig(
                    number=n + 1,
                    cob_id=cob_id & 0x1FFFFFFF if cob_id & 0x20000000 else cob_id & 0x7FF,
                    valid=not cob_id & 0x80000000,
                    transmission_type=self._read(comm, 2) or 0,
                    inhibit_100us=self._read(comm, 3) or 0,
                    event_timer_ms=self._read(comm, 5) or 0,
                    mapping=entries,
                )
            )
        return configs

    def start(self) -> None:
        """Enter operational: (re)load the configuration and arm timers."""
        self.stop()
        self._configs = [c for c in self._load() if c.valid and c.mapping]
        self.running = True
        for config in self._configs:
            if config.transmission_type in (254, 255) and config.event_timer_ms > 0:
                period = config.event_timer_ms / 1000
                self._jobs.append(
                    self._scheduler.call_later(period, lambda c=config: self._transmit(c), period)
                )
        if any(self._on_change(c) for c in self._configs):
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

    def _on_change(self, config: TpdoConfig) -> bool:
        if config.transmission_type == 255 and config.event_timer_ms == 0 and self._timer_zero_disables_255:
            return False
        return config.transmission_type in (254, 255)

    def on_sync(self) -> None:
        if not self.running:
            return
        for config in self._configs:
            kind = config.transmission_type
            if 1 <= kind <= 240:
                config.sync_count += 1
                if config.sync_count >= kind:
                    config.sync_count = 0
                    self._transmit(config)
            elif kind == 0 and self._payload(config) != config.last_payload:
                self._transmit(config)

    def _poll_changes(self) -> None:
        for config in self._configs:
            if self._on_change(config) and self._payload(config) != config.last_payload:
                self._transmit(config)

    def _payload(self, config: TpdoConfig) -> bytes:
        data = b"".join(self._mapped_bytes(i, s, bits) for i, s, bits in config.mapping)
        return data[:8]

    def _transmit(self, config: TpdoConfig) -> None:
        if not self.running:
            return
        now = time.monotonic()
        if config.inhibit_100us and now - config.last_sent < config.inhibit_100us / 10000:
            return
        payload = self._payload(config)
        config.last_payload = payload
        config.last_sent = now
        self._send(config.cob_id, payload)
