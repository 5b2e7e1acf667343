"""Quirk ``guarding_heartbeat_exclusive``: node guarding and the heartbeat producer exclude each other.

FAULHABER MC (3.8.2.1, 3.8.3): a producer heartbeat time > 0 sets the guard time to 0, and a
guard time written while the producer runs is refused. CiA 301 keeps the objects independent.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .faults import FaultSet
from .nvm import Key
from .sdo_server import SdoAbort


@dataclass(frozen=True)
class GuardingHeartbeatExclusion:
    producer: Key
    guard_time: Key
    abort_code: int
    faults: FaultSet

    @classmethod
    def from_params(cls, params: dict[str, Any], faults: FaultSet) -> GuardingHeartbeatExclusion:
        return cls(
            producer=(int(params.get("producer_object", 0x1017)), 0),
            guard_time=(int(params.get("guard_time_object", 0x100C)), 0),
            abort_code=int(params.get("guard_time_write_while_producer_abort", 0x08000020)),
            faults=faults,
        )

    def _active(self) -> bool:
        return not self.faults.active("guarding_heartbeat_coexist")

    def gate(self, key: Key, value: object, read: Callable[[int, int], int | None]) -> None:
        """Refuse a non-zero guard time while the heartbeat producer runs (writing 0 stays allowed)."""
        if self._active() and key == self.guard_time and value != 0 and (read(*self.producer) or 0) > 0:
            raise SdoAbort(self.abort_code)

    def after_write(self, key: Key, value: object, write: Callable[[Key, int], None]) -> None:
        """A producer time > 0 switches node guarding off (guard time 0)."""
        if self._active() and key == self.producer and isinstance(value, int) and value > 0:
            write(self.guard_time, 0)
