"""Interval statistics for periodic frames (heartbeat, event timers), judged with profile tolerances."""

from __future__ import annotations

import itertools
import statistics
from dataclasses import dataclass


@dataclass(frozen=True)
class IntervalStats:
    period_ms: float
    intervals_ms: tuple[float, ...]

    @property
    def count(self) -> int:
        return len(self.intervals_ms)

    @property
    def mean_ms(self) -> float:
        return statistics.fmean(self.intervals_ms)

    @property
    def median_ms(self) -> float:
        return statistics.median(self.intervals_ms)

    @property
    def worst_error_ms(self) -> float:
        return max(abs(i - self.period_ms) for i in self.intervals_ms)

    def outside(self, tolerance_ms: float) -> list[tuple[int, float]]:
        """(position, interval) of every interval off by more than the tolerance."""
        return [(n, i) for n, i in enumerate(self.intervals_ms) if abs(i - self.period_ms) > tolerance_ms]

    def csv(self) -> str:
        return "n,interval_ms\n" + "\n".join(f"{n},{i:.3f}" for n, i in enumerate(self.intervals_ms))


def interval_stats(timestamps: list[float], period_ms: float) -> IntervalStats:
    """Intervals between consecutive timestamps (seconds in, milliseconds out)."""
    intervals = tuple((b - a) * 1000 for a, b in itertools.pairwise(timestamps))
    return IntervalStats(period_ms, intervals)
