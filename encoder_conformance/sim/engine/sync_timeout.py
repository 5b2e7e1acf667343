"""The SYNC consumer's time-out (CiA 301 v4.2.0 §7.5.2.6 object 1006h).

A behaviour the default twin keeps idle: 1006h is the SYNC producer's period, and a consumer need not watch it.
Its variant plays the other reading, as CANopenNode does: with 1006h above 0, no SYNC for one and a half periods
records the communication error 8100h (1001h bit 4) and sends its EMCY, once (in pre-operational or operational; the
time counts from the last SYNC or the boot-up, not from the write of 1006h, so that 1006h written after a while
without SYNC times out at once). The error stays until a reset (NMT reset communication or reset node reloads 1001h),
also after 1006h went back to 0, and while it is active the node falls back from operational to pre-operational
(CiA 301's default error behaviour, ``nmt_error_behaviour``), also right after an NMT start.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from encoder_conformance.cia.cia301 import COMMUNICATION_CYCLE_PERIOD, EmcyCode
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nmt_error_behaviour import CommErrorBehaviour, Nmt
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler, JobHandle
from encoder_conformance.sim.engine.sync_objects import COMMUNICATION_ERROR_BIT, Read


class SyncTimeoutMonitor(CommErrorBehaviour):
    """Watches the time since the last SYNC against 1006h, where a variant says the consumer does."""

    def __init__(self, scheduler: DeadlineScheduler, read: Read, nmt: Nmt,
                 raise_error: Callable[[int, int], None], lock: threading.RLock) -> None:
        super().__init__(scheduler, read, nmt, lock)
        self._raise_error = raise_error
        self._job: JobHandle | None = None
        self._raised = False
        self._last_sync = time.monotonic()

    def register(self, hooks: NodeHooks) -> None:
        super().register(hooks)
        hooks.sync.append(self.on_sync)
        hooks.on_written(self.on_write, [COMMUNICATION_CYCLE_PERIOD])
        hooks.booted.append(self.on_boot)
        hooks.halted.append(self.stop)

    def monitors(self) -> bool:
        """Whether the consumer watches 1006h (the default twin: no)."""
        return False

    def leaves_operational(self) -> bool:
        return self.monitors()

    def on_boot(self) -> None:
        self._raised = False
        self._last_sync = time.monotonic()
        self.arm()

    def on_write(self, key: Key, value: Value) -> None:
        self.arm()

    def on_sync(self, counter: int | None) -> None:
        self._last_sync = time.monotonic()
        self.arm()

    def stop(self) -> None:
        if self._job is not None:
            self._job.cancel()
            self._job = None

    def arm(self) -> None:
        self.stop()
        period_us = self._read(COMMUNICATION_CYCLE_PERIOD, 0) or 0
        if self.monitors() and period_us > 0:
            due = max(time.monotonic(), self._last_sync + 1.5 * period_us / 1e6)
            self._job = self._scheduler.call_at(due, self._timed_out)

    def _timed_out(self) -> None:
        with self._lock:
            self._job = None
            if self._raised or self._nmt.state not in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL):
                return
            self._raised = True
            self._raise_error(EmcyCode.COMMUNICATION, COMMUNICATION_ERROR_BIT)
            self.check()


@breaks(SyncTimeoutMonitor, "sync_timeout_error")
class SyncTimeoutRaised(SyncTimeoutMonitor):
    """A variant, not a fault: the consumer watches 1006h (CANopenNode)."""

    def monitors(self) -> bool:
        return True
