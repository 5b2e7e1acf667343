"""Linear scales and round tick values for the hand-written timing plot (timing_plot.py): data values to
pixels, and a few ticks at 1, 2, 2.5 or 5 times a power of ten, as a reader expects on an axis."""

from __future__ import annotations

import math
from dataclasses import dataclass

MARGIN = 0.05  # of the data range on each side, as matplotlib's default axes margins


@dataclass(frozen=True)
class Scale:
    """Maps [lo, hi] in data to [start, end] in pixels (end < start for a y axis: SVG's y grows downwards)."""

    lo: float
    hi: float
    start: float
    end: float

    @classmethod
    def padded(cls, lo: float, hi: float, start: float, end: float) -> Scale:
        """A scale over [lo, hi] widened by MARGIN; an empty range becomes one unit around it (no zero span)."""
        if not hi > lo:
            lo, hi = lo - 0.5, hi + 0.5
        pad = (hi - lo) * MARGIN
        return cls(lo - pad, hi + pad, start, end)

    def __call__(self, value: float) -> float:
        return self.start + (value - self.lo) / (self.hi - self.lo) * (self.end - self.start)

    def ticks(self, count: int = 5, integer: bool = False) -> list[float]:
        """About ``count`` round values inside the scale (whole numbers only, when ``integer``)."""
        step = nice_step((self.hi - self.lo) / count)
        if integer:
            step = max(step, 1.0)
        first = math.ceil(self.lo / step)
        return [k * step for k in range(first, math.floor(self.hi / step) + 1)]


def nice_step(raw: float) -> float:
    """The smallest of 1, 2, 2.5, 5, 10 times a power of ten that is at least ``raw``."""
    if not raw > 0 or not math.isfinite(raw):
        return 1.0
    power = 10.0 ** math.floor(math.log10(raw))
    return next(m * power for m in (1, 2, 2.5, 5, 10) if m * power >= raw * (1 - 1e-9))


def tick_labels(ticks: list[float]) -> list[str]:
    """The labels of evenly spaced ``ticks``, all with the decimals their step needs."""
    step = ticks[1] - ticks[0] if len(ticks) > 1 else 1.0
    return [tick_label(value, step) for value in ticks]


def tick_label(value: float, step: float) -> str:
    """``value`` with as many decimals as ``step`` needs (2.5 needs one more than 2), never "-0"."""
    decimals = max(0, -math.floor(math.log10(step) + 1e-9)) if step > 0 else 0
    if round(step / 10.0 ** -decimals, 6) % 1:
        decimals += 1
    text = f"{value:.{decimals}f}"
    return text[1:] if text.lstrip("-0.") == "" and text.startswith("-") else text
