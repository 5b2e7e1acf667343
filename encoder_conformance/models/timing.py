"""Timing statistics: intervals of periodic frames (heartbeat, event timers, inhibit spacing) and latencies
(SYNC to TPDO), summarised the same way and judged with profile tolerances."""

from __future__ import annotations

import itertools
import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass


def percentile(values: Sequence[float], share: float) -> float:
    """The ``share`` (0..1, in whole percents) percentile: ``statistics.quantiles`` with ``method="inclusive"``,
    linear interpolation between the closest ranks (numpy's default), so that p50 is the median and p100 the
    maximum for any count. The project's one percentile: the device's timing figures and the tester host's
    lateness (dut/latency_probe.py) are both computed with it."""
    percent = round(share * 100)
    if not 0 <= percent <= 100 or abs(share * 100 - percent) > 1e-9:
        raise ValueError(f"a percentile in whole percents from 0 to 1, not {share}")
    if not values:
        return math.nan
    if len(values) == 1 or percent in (0, 100):
        return max(values) if percent else min(values)
    return statistics.quantiles(values, n=100, method="inclusive")[percent - 1]


@dataclass(frozen=True)
class TimingSummary:
    """Count, mean, p50, p95, p99 and max of timing samples (intervals or latencies, ms), with their error
    against the nominal value (the period, or 0 for a latency)."""

    count: int
    mean: float
    p50: float
    p95: float
    p99: float
    min: float
    max: float
    nominal: float

    @classmethod
    def of(cls, samples: list[float] | tuple[float, ...], nominal: float) -> TimingSummary:
        if not samples:
            return cls(0, *(math.nan,) * 6, nominal)
        return cls(len(samples), statistics.fmean(samples), percentile(samples, 0.5), percentile(samples, 0.95),
                   percentile(samples, 0.99), min(samples), max(samples), nominal)

    @property
    def p99_error(self) -> float:
        """The p99 sample's distance from the nominal value (signed)."""
        return self.p99 - self.nominal

    @property
    def worst_error(self) -> float:
        """The largest distance of any sample from the nominal value (unsigned)."""
        return max(abs(self.max - self.nominal), abs(self.min - self.nominal))

    def figures(self) -> dict[str, float]:
        """The figures by name, for tables and properties."""
        return {"count": self.count, "mean": self.mean, "p50": self.p50, "p95": self.p95, "p99": self.p99,
                "max": self.max, "min": self.min, "nominal": self.nominal, "worst error": self.worst_error}


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


@dataclass(frozen=True)
class ScheduleFit:
    """Frame times against the best straight-line schedule t = t0 + n * period (Theil-Sen: the median of
    the pairwise slopes, and the median intercept).

    A frame delayed once (bus arbitration, a busy tester) moves two intervals (+d, -d) but only
    itself off the schedule: counting frames off the schedule tells one late frame from a device
    whose timer drifts or jitters on every cycle. The medians keep a few delayed frames from moving the
    schedule itself (a least-squares line, pulled by three frames a stalled host sent 12-62 ms late at the
    start of a capture, put the punctual frames after them 7 ms "early": a good twin failed in CI).
    """

    period_ms: float
    fitted_period_ms: float
    offsets_ms: tuple[float, ...]  # each frame's distance from the fitted schedule

    def off_schedule(self, tolerance_ms: float) -> list[tuple[int, float]]:
        """(frame number, offset) of the frames further than ``tolerance_ms`` from the schedule."""
        return [(n, o) for n, o in enumerate(self.offsets_ms) if abs(o) > tolerance_ms]


def schedule_fit(timestamps: list[float], period_ms: float) -> ScheduleFit:
    """Fit t = t0 + n * p to the timestamps (seconds), robust to a minority of delayed frames (Theil-Sen);
    offsets in milliseconds."""
    count = len(timestamps)
    slopes = [(timestamps[j] - timestamps[i]) / (j - i) for i in range(count) for j in range(i + 1, count)]
    slope = statistics.median(slopes) if slopes else 0.0
    start = statistics.median(t - slope * n for n, t in enumerate(timestamps)) if timestamps else 0.0
    offsets = tuple((t - (start + slope * n)) * 1000 for n, t in enumerate(timestamps))
    return ScheduleFit(period_ms, slope * 1000, offsets)


def interval_stats(timestamps: list[float], period_ms: float) -> IntervalStats:
    """Intervals between consecutive timestamps (seconds in, milliseconds out)."""
    intervals = tuple((b - a) * 1000 for a, b in itertools.pairwise(timestamps))
    return IntervalStats(period_ms, intervals)
