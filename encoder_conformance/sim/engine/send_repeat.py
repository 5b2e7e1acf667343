"""Manufacturer send-repeat counters of TPDOs (quirk effect ``pdo_send_repeat_counters``).

Example (SIKO WV58M/WH58M, M §4.2.1, §4.2.2, §7.2):

- ``tpdo1`` (2800h, PDO1 transmission type 254): counter 0 = the TPDO follows its event timer
  only (timer 0 = not sent at all, no change-driven sending); counter n >= 1 with event timer 0 =
  each position change seen by the engine's change poll sends the TPDO n times, one frame per
  poll; with a running event timer the counter is ignored (the timer wins).
- ``tpdo2`` (2801h, PDO2 every n-th SYNC): counter 0 = no limit; k >= 1 = only k SYNC-driven
  frames; the count restarts when the payload (position) differs from the last one sent, and
  whenever the engine reloads (NMT reset, entering operational, a PDO parameter written).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from encoder_conformance.profile.quirk_effects import PdoSendRepeatCounters
from encoder_conformance.sim.engine.tpdo_config import TpdoConfig

Read = Callable[[int, int], int | None]


@dataclass(frozen=True)
class SendRepeatCounters:
    per_change: dict[int, int]  # comm index -> counter object: sends per position change
    sync_limit: dict[int, int]  # comm index -> counter object: SYNC-driven sends in all
    counter_max: int

    @classmethod
    def from_params(cls, params: PdoSendRepeatCounters) -> SendRepeatCounters:
        return cls(params.per_change, params.sync_limit, params.counter_max)

    @property
    def counter_objects(self) -> frozenset[int]:
        """Objects whose write changes a TPDO's behaviour (the engine reloads on them)."""
        return frozenset(self.per_change.values()) | frozenset(self.sync_limit.values())

    def _value(self, read: Read, index: int) -> int:
        return max(0, min(read(index, 0) or 0, self.counter_max))

    def configure(self, comm: int, config: TpdoConfig, read: Read) -> None:
        """Apply the counters to a freshly loaded configuration (CiA semantics already applied)."""
        if comm in self.per_change and config.transmission_type in (254, 255):
            sends = self._value(read, self.per_change[comm])
            config.on_change = sends > 0 and config.event_timer_ms == 0
            config.sends_per_change = max(sends, 1)
        if comm in self.sync_limit and config.sync_every:
            config.sync_limit = self._value(read, self.sync_limit[comm])


def within_sync_limit(config: TpdoConfig, payload: bytes) -> bool:
    """A SYNC-driven send is due: may it go out? Counts it; a changed payload restarts the count."""
    if not config.sync_limit:
        return True
    if payload != config.last_payload:
        config.sync_sent = 0
    if config.sync_sent >= config.sync_limit:
        return False
    config.sync_sent += 1
    return True
