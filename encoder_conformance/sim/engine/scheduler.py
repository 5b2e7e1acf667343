"""One timing thread with a heap of absolute deadlines (heartbeat, event timers, boot-up delays).

Absolute deadlines do not drift: a periodic job is re-armed at ``previous_deadline + period``,
not at ``now + period`` (reference/python-stack-measured.md §6).
"""

from __future__ import annotations

import heapq
import itertools
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass(order=True)
class _Job:
    due: float
    seq: int
    action: Callable[[], None] = field(compare=False)
    period: float | None = field(compare=False, default=None)
    cancelled: bool = field(compare=False, default=False)


class JobHandle:
    """Returned by the scheduler; ``cancel()`` stops the job."""

    def __init__(self, job: _Job) -> None:
        self._job = job

    def cancel(self) -> None:
        self._job.cancelled = True

    @property
    def active(self) -> bool:
        return not self._job.cancelled


class DeadlineScheduler:
    """Runs callbacks at absolute monotonic times on one daemon thread."""

    def __init__(self, name: str = "sim-scheduler") -> None:
        self._heap: list[_Job] = []
        self._seq = itertools.count()
        self._cond = threading.Condition()
        self._stopped = False
        #: (time.time() when a job ran, how late in ms): a twin on an overloaded host is late itself, and a
        #: timing verdict must not blame the device for it (the tester asks through the control channel)
        self.lateness: deque[tuple[float, float]] = deque(maxlen=8192)
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def call_at(self, due: float, action: Callable[[], None], period: float | None = None) -> JobHandle:
        """Run ``action`` at monotonic time ``due`` (and every ``period`` s after, if given)."""
        job = _Job(due, next(self._seq), action, period)
        with self._cond:
            heapq.heappush(self._heap, job)
            self._cond.notify()
        return JobHandle(job)

    def call_later(self, delay: float, action: Callable[[], None], period: float | None = None) -> JobHandle:
        return self.call_at(time.monotonic() + delay, action, period)

    def note_lateness(self, late_ms: float) -> None:
        """Lateness of the twin met outside this thread (e.g. a received frame handled late)."""
        self.lateness.append((time.time(), late_ms))

    def lateness_since(self, wall_time: float) -> list[tuple[float, float]]:
        """(time.time(), lateness ms) of every job run after ``wall_time``."""
        return [entry for entry in list(self.lateness) if entry[0] >= wall_time]

    def stop(self) -> None:
        with self._cond:
            self._stopped = True
            self._cond.notify()
        self._thread.join(timeout=2)

    def _run(self) -> None:
        while True:
            with self._cond:
                while not self._stopped and (not self._heap or self._heap[0].due > time.monotonic()):
                    timeout = self._heap[0].due - time.monotonic() if self._heap else None
                    self._cond.wait(timeout)
                if self._stopped:
                    return
                job = heapq.heappop(self._heap)
                if job.cancelled:
                    continue
                due = job.due
                if job.period:
                    job.due += job.period
                    heapq.heappush(self._heap, job)
            try:
                job.action()
                # measured once the job has run (its frames are stamped): how late they went out
                self.lateness.append((time.time(), (time.monotonic() - due) * 1000))
            except Exception:  # a faulty job must not kill the timing thread
                import logging

                logging.getLogger(__name__).exception("scheduled job failed")
