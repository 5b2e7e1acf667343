"""The plot of one timing measurement: the samples in order with the nominal line and the limit band, and
their histogram beside it. matplotlib's object API on the Agg canvas (no pyplot, no global backend),
imported only when a timing test reports; small PNGs (~20-30 kB) so a report stays light."""

from __future__ import annotations

import io
from collections.abc import Sequence

WIDTH_IN, HEIGHT_IN, DPI = 7.0, 2.4, 80
HISTOGRAM_BINS = 40


def render_png(name: str, samples: Sequence[float], nominal: float, low: float | None, high: float | None,
               sample_label: str = "sample", unit: str = "ms") -> bytes:
    """PNG of ``samples`` in order (outside [low, high] in red) and their histogram, with the band and nominal."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(WIDTH_IN, HEIGHT_IN), dpi=DPI)
    figure.subplots_adjust(left=0.08, right=0.98, bottom=0.18, top=0.88, wspace=0.04)
    FigureCanvasAgg(figure)
    series, histogram = figure.subplots(1, 2, sharey=True, width_ratios=[3, 1])
    values = [*samples, nominal, *(v for v in (low, high) if v is not None)]
    span = (max(values) - min(values)) or 1.0
    bottom = low if low is not None else min(values) - 0.1 * span
    top = high if high is not None else max(values) + 0.1 * span
    for axes in (series, histogram):
        axes.axhspan(bottom, top, color="#2a2", alpha=0.12, lw=0)
        for limit in (low, high):
            if limit is not None:
                axes.axhline(limit, color="#2a2", lw=0.8, ls="--")
        axes.axhline(nominal, color="#555", lw=0.8)
        axes.grid(alpha=0.3, lw=0.5)
    inside = [(n, v) for n, v in enumerate(samples) if _within(low, high, v)]
    outside = [(n, v) for n, v in enumerate(samples) if not _within(low, high, v)]
    series.plot(range(len(samples)), samples, color="#369", lw=0.8)
    if inside:
        series.scatter(*zip(*inside, strict=True), s=6, color="#369", zorder=3)
    if outside:
        series.scatter(*zip(*outside, strict=True), s=14, color="#c00", zorder=4)
    series.set_xlabel(f"{sample_label} #", fontsize=8)
    series.set_ylabel(unit, fontsize=8)
    series.set_title(name, fontsize=9, loc="left")
    # bins of one width across the whole visible range, so that tight samples pile up into a visible bar
    # (bins over the samples' own range would be too thin to see against the band)
    low_edge, high_edge = min([bottom, *samples]), max([top, *samples])
    edges = [low_edge + (high_edge - low_edge) * k / HISTOGRAM_BINS for k in range(HISTOGRAM_BINS + 1)]
    histogram.hist(samples, bins=edges, orientation="horizontal", color="#369")
    histogram.set_xlabel("count", fontsize=8)
    for axes in (series, histogram):
        axes.tick_params(labelsize=7)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=DPI)
    return buffer.getvalue()


def _within(low: float | None, high: float | None, value: float) -> bool:
    return (low is None or value >= low) and (high is None or value <= high)
