"""How late the tester's own host runs while a timing measurement is taken.

Frame timestamps on a twin or a software-stamped adapter are taken by processes on the tester's
host; when that host is overloaded, a frame looks late although the device sent it on time. The
probe is a thread that asks to wake every ``TICK_S`` and records how late each wake-up came: a
direct measure of the host's scheduling latency during the capture. A timing verdict that fails
while the probe saw lateness beyond the tolerance is inconclusive, not a device failure.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from encoder_conformance.models.timing import percentile

TICK_S = 0.005
#: a wall clock that moved less than this against the monotonic clock over a capture is not worth a word (reading
#: the two clocks one after the other, and a clock being slewed, move it by microseconds)
CLOCK_STEP_WORTH_SAYING_MS = 1.0
#: the simulated twin's own lateness since a time.time(): (when, ms late) of each job its timing thread ran
TwinLateness = Callable[[float], list[tuple[float, float]]]


@dataclass(frozen=True)
class HostLatency:
    """The probe's wake-up lateness over a capture window (milliseconds), and when each came (wall clock,
    the clock of frame timestamps). ``p95_ms`` is the one percentile of the device's figures too
    (``models.timing.percentile``)."""

    samples: int
    worst_ms: float
    p95_ms: float
    wakeups: tuple[tuple[float, float], ...] = ()  # (time.time(), lateness ms)
    twin_worst_ms: float | None = None  # the simulated twin's timing thread (same host), where there is one
    #: how far the wall clock (the clock of frame timestamps) moved against the monotonic clock during the capture:
    #: a step of it (NTP, a virtual machine's clock correction) makes a frame look seconds off its schedule
    clock_step_ms: float = 0.0

    def worst_near(self, when: float, window_s: float) -> float:
        """The latest wake-up (ms) within ``window_s`` of ``when``."""
        return max((late for t, late in self.wakeups if abs(t - when) <= window_s), default=0.0)

    def describe(self) -> str:
        twin = "" if self.twin_worst_ms is None else \
            f"; the simulated twin's timing thread ran up to {self.twin_worst_ms:.1f} ms late"
        step = "" if self.clock_step_ms < CLOCK_STEP_WORTH_SAYING_MS else \
            f"; the wall clock moved {self.clock_step_ms:.1f} ms against the monotonic clock"
        return f"the tester's own {TICK_S * 1000:.0f} ms timer woke up to {self.worst_ms:.1f} ms late " \
               f"(p95 {self.p95_ms:.1f} ms, {self.samples} wake-ups){twin}{step}"

    def sustained(self, tolerance_ms: float) -> bool:
        """True when the host ran later than ``tolerance_ms`` for more than 5 % of the window."""
        return self.p95_ms > tolerance_ms


class LatencyProbe:
    """Context manager: ``with LatencyProbe() as probe: ...; probe.result()``. With ``twin`` (the simulator's
    control channel), the twin's own scheduling lateness on the same host counts too: a twin that ran late
    sends late frames, and that is the host's doing, not the device's."""

    def __init__(self, twin: TwinLateness | None = None) -> None:
        self._twin = twin
        self._twin_wakeups: list[tuple[float, float]] | None = None
        self._started = time.time()
        self._wakeups: list[tuple[float, float]] = []
        self._offsets: list[float] = []  # time.time() - time.perf_counter() at each wake-up
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="host-latency-probe", daemon=True)

    def __enter__(self) -> LatencyProbe:
        self._started = time.time()
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(1.0)
        if self._twin is not None:
            # as tuples (a channel may hand pairs over as lists), to sort with the tester's own
            self._twin_wakeups = [(when, late) for when, late in self._twin(self._started)]

    def _run(self) -> None:
        while True:
            due = time.perf_counter() + TICK_S
            if self._stop.wait(TICK_S):
                return
            now, wall = time.perf_counter(), time.time()
            self._wakeups.append((wall, max(0.0, (now - due) * 1000)))
            self._offsets.append(wall - now)

    def result(self) -> HostLatency:
        """The tester's lateness (samples, worst, p95); ``worst_near`` also sees the twin's."""
        twin = self._twin_wakeups
        wakeups = tuple(sorted(self._wakeups + (twin or [])))
        late = [ms for _, ms in self._wakeups]
        twin_worst = max((ms for _, ms in twin), default=0.0) if twin is not None else None
        step_ms = (max(self._offsets) - min(self._offsets)) * 1000 if self._offsets else 0.0
        if not late:
            return HostLatency(0, 0.0, 0.0, wakeups, twin_worst, step_ms)
        return HostLatency(len(late), max(late), percentile(late, 0.95), wakeups, twin_worst, step_ms)
