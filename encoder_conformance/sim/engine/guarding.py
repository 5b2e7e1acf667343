"""Quirk ``guarding_heartbeat_exclusive``: node guarding and the heartbeat producer exclude each other.

FAULHABER MC (3.8.2.1, 3.8.3): a producer heartbeat time > 0 sets the guard time to 0, and a
guard time written while the producer runs is refused. CiA 301 keeps the objects independent.
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.profile.quirk_effects import GuardingHeartbeatExclusive
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.sdo_server import SdoAbort


class GuardingHeartbeatExclusion:
    """A behaviour: gates guard-time writes and switches guarding off when the producer starts."""

    def __init__(self, producer: Key, guard_time: Key, abort_code: int, read: Callable[[int, int], int | None],
                 write: Callable[[Key, int], None]) -> None:
        self.producer = producer
        self.guard_time = guard_time
        self.abort_code = abort_code
        self._read = read
        self._write = write

    @classmethod
    def from_params(cls, params: GuardingHeartbeatExclusive, read: Callable[[int, int], int | None],
                    write: Callable[[Key, int], None]) -> GuardingHeartbeatExclusion:
        return cls(
            producer=(params.producer_object, 0),
            guard_time=(params.guard_time_object, 0),
            abort_code=params.guard_time_write_while_producer_abort,
            read=read,
            write=write,
        )

    def register(self, hooks: NodeHooks) -> None:
        hooks.gates.append(self.gate)
        hooks.on_written(self.after_write, [self.producer[0]])

    def excludes(self) -> bool:
        return True

    def gate(self, key: Key, value: object) -> None:
        """Refuse a non-zero guard time while the heartbeat producer runs (writing 0 stays allowed)."""
        if self.excludes() and key == self.guard_time and value != 0 and (self._read(*self.producer) or 0) > 0:
            raise SdoAbort(self.abort_code)

    def after_write(self, key: Key, value: object) -> None:
        """A producer time > 0 switches node guarding off (guard time 0)."""
        if self.excludes() and key == self.producer and isinstance(value, int) and value > 0:
            self._write(self.guard_time, 0)


@breaks(GuardingHeartbeatExclusion, "guarding_heartbeat_coexist")
class GuardingCoexists(GuardingHeartbeatExclusion):
    def excludes(self) -> bool:
        return False
