"""The SYNC producer (CiA 301 v4.2.0 §7.5.2.5 object 1005h, §7.5.2.6 object 1006h).

A behaviour: while 1005h bit 30 (gen) is set and 1006h (communication cycle period, µs) is above 0, the node sends a
SYNC on the 1005h CAN-ID every 1006h µs, with the counter byte where 1019h is above 0, in pre-operational and
operational (SYNC is no PDO: CiA 301 §7.3.2.2). 1006h = 0 stops it. Only a node that may produce SYNC gets bit 30
set: the 1005h write gate (``sync_objects.SyncCobIdRules``) refuses it elsewhere.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from encoder_conformance.cia.cia301 import (
    COB_ID_FRAME_29_BIT,
    COB_ID_SYNC_GENERATE,
    COMMUNICATION_CYCLE_PERIOD,
    SYNC_COB_ID,
    SYNC_COB_ID_OBJECT,
    SYNC_COUNTER_OVERFLOW,
)
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler, JobHandle

#: the variant that generates SYNC (``sync_producer``) sends its first SYNC this long after the 1005h/1006h write,
#: as CANopenNode's Linux demo did (49 ms after 1006h = 10 ms), doubled: later than a measured silence window, within
#: the answer window the suite waits for a first SYNC (test_sync_objects' producer test)
FIRST_SYNC_LATE_S = 0.1

Read = Callable[[int, int], int | None]
SendSync = Callable[[int, bytes, bool], None]


class SyncProducer:
    """Sends SYNC every 1006h µs while 1005h bit 30 is set; (re)started by writes of 1005h/1006h and state changes."""

    def __init__(self, scheduler: DeadlineScheduler, read: Read, send: SendSync,
                 state: Callable[[], NmtState | None], lock: threading.RLock) -> None:
        self._scheduler = scheduler
        self._read = read
        self._send = send
        self._state = state
        self._lock = lock
        self._job: JobHandle | None = None
        self._counter = 0

    def register(self, hooks: NodeHooks) -> None:
        hooks.on_written(self.on_write, [SYNC_COB_ID_OBJECT, COMMUNICATION_CYCLE_PERIOD])
        hooks.booted.append(self.restart)
        hooks.halted.append(self.stop)
        hooks.state.append(lambda state: self.restart())

    def on_write(self, key: Key, value: Value) -> None:
        self.restart()

    def period_s(self) -> float:
        """The SYNC period in force (0: no SYNC): 1006h while 1005h bit 30 is set."""
        cob_id = self._read(SYNC_COB_ID_OBJECT, 0) or 0
        if not cob_id & COB_ID_SYNC_GENERATE:
            return 0.0
        return (self._read(COMMUNICATION_CYCLE_PERIOD, 0) or 0) / 1e6

    def stop(self) -> None:
        if self._job is not None:
            self._job.cancel()
            self._job = None

    def restart(self) -> None:
        self.stop()
        period = self.period_s()
        if period > 0 and self._state() in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL):
            self._counter = 0
            self._job = self._scheduler.call_at(time.monotonic() + self.first_after_s(period), self._tick, period)

    def first_after_s(self, period: float) -> float:
        """How long after a (re)start the first SYNC comes: one period."""
        return period

    def _tick(self) -> None:
        with self._lock:
            cob_id = self._read(SYNC_COB_ID_OBJECT, 0)
            cob_id = SYNC_COB_ID if cob_id is None else cob_id
            extended = bool(cob_id & COB_ID_FRAME_29_BIT)
            overflow = self._read(SYNC_COUNTER_OVERFLOW, 0) or 0
            data = b""
            if overflow:
                self._counter = self._counter % overflow + 1
                data = bytes([self._counter])
            self._send(cob_id & (0x1FFFFFFF if extended else 0x7FF), data, extended)


@breaks(SyncProducer, "sync_producer_never_stops")
class SyncProducerNeverStops(SyncProducer):
    """1006h = 0 leaves the SYNC running at its last period."""

    def restart(self) -> None:
        if self._job is not None and self.period_s() <= 0:
            return
        super().restart()


@breaks(SyncProducer, "sync_producer")
class SyncProducerFirstLate(SyncProducer):
    """The variant that generates SYNC (its 1005h gate: ``sync_objects.SyncProducerVariant``) sends its first SYNC
    ``FIRST_SYNC_LATE_S`` after a (re)start, as CANopenNode's demo (CiA 301 bounds only the period)."""

    def first_after_s(self, period: float) -> float:
        return FIRST_SYNC_LATE_S


#: how late ``sync_late_after_stop`` sends its last SYNC: after the tester's window on every shipped profile (as
#: ``sdo_channel.LATE_ANSWER_S``)
LATE_SYNC_S = 0.33


@breaks(SyncProducer, "sync_late_after_stop")
class SyncLateAfterStop(SyncProducer):
    """1006h = 0 stops the SYNC, but one more comes ``LATE_SYNC_S`` later (only the late-frame ledger sees it)."""

    def restart(self) -> None:
        running = self._job is not None
        super().restart()
        if running and self._job is None:
            self._scheduler.call_later(LATE_SYNC_S, self._tick)
