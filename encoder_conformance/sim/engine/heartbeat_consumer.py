"""The heartbeat consumer (1016h, CiA 301 §7.2.8.3.2.2): each entry watches one producer's heartbeat.

A behaviour: an entry with a node-ID of 1..127 and a time other than 0 starts watching at the first heartbeat of
that producer after it was written (CiA 301: monitoring starts with the first heartbeat received); silence for
longer than the time is a heartbeat event: the error 8130h (or the code the profile's quirk documents) is recorded
and its EMCY sent, once, until the producer's next heartbeat re-arms the entry. Writing the entry or leaving the
node (reset, power off) stops the watch.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

from encoder_conformance.cia.cia301 import HEARTBEAT_CONSUMER, EmcyCode
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler, JobHandle
from encoder_conformance.sim.engine.sync_objects import COMMUNICATION_ERROR_BIT, Read


class HeartbeatConsumer:
    def __init__(self, scheduler: DeadlineScheduler, read: Read, entries: int,
                 raise_error: Callable[[int, int], None], code: int = EmcyCode.HEARTBEAT) -> None:
        self._scheduler = scheduler
        self._read = read
        self._entries = entries
        self._raise_error = raise_error
        self._code = code
        self._watches: dict[int, JobHandle] = {}  # sub-index -> the time-out job

    def register(self, hooks: NodeHooks) -> None:
        hooks.on_written(self._on_write, [HEARTBEAT_CONSUMER])
        hooks.heartbeat.append(self.on_heartbeat)
        hooks.halted.append(self.stop)

    def _on_write(self, key: Key, value: Value) -> None:
        self._stop_one(key[1])

    def stop(self) -> None:
        for sub in list(self._watches):
            self._stop_one(sub)

    def _stop_one(self, sub: int) -> None:
        job = self._watches.pop(sub, None)
        if job is not None:
            job.cancel()

    def on_heartbeat(self, producer: int) -> None:
        """A heartbeat of node ``producer``: (re)start the time-out of every entry that watches it."""
        for sub in range(1, self._entries + 1):
            entry = self._read(HEARTBEAT_CONSUMER, sub) or 0
            node, time_ms = entry >> 16 & 0xFF, entry & 0xFFFF
            if node != producer or not time_ms:
                continue
            self._stop_one(sub)
            self._watches[sub] = self._scheduler.call_later(time_ms / 1000, partial(self._timed_out, sub))

    def _timed_out(self, sub: int) -> None:
        self._watches.pop(sub, None)
        self.heartbeat_event()

    def heartbeat_event(self) -> None:
        self._raise_error(self._code, COMMUNICATION_ERROR_BIT)


@breaks(HeartbeatConsumer, "heartbeat_consumer_timeout_silent")
class HeartbeatConsumerTimeoutSilent(HeartbeatConsumer):
    def heartbeat_event(self) -> None:
        pass
