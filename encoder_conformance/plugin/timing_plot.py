"""The plot of one timing measurement: the samples in order with the nominal line and the limit band, and
their histogram beside it, as a self-contained SVG (560 x 192 px, the size of the former 7 x 2.4 in at 80 dpi).

Hand-written rather than drawn with a plotting library: the chart is two panels of lines, dots and bars, and
matplotlib (which drew it before) cost ~1 s to import and 0.2-0.5 s of CPU per plot (the lower figure on a
developer machine, the higher on the loaded 2-core CI): 1.5-3 s of a 30 s full run, on a CI that runs ~30
such runs. This renderer takes ~1 ms per plot of 50 samples (~4 ms for 1000) and adds no dependency; the SVG
is 5-10 kB of text for 50 samples, about half the former PNG (the report embeds it as an image)."""

from __future__ import annotations

import html
from collections.abc import Sequence

from encoder_conformance.plugin.plot_scale import Scale, tick_labels

WIDTH, HEIGHT = 560, 192
HISTOGRAM_BINS = 40
PLOT_TOP, PLOT_BOTTOM = 23.0, 157.0
SERIES_X = (45.0, 415.0)  # the panels' widths in the ratio 3:1, a narrow gap between
HISTOGRAM_X = (425.0, 549.0)
BLUE, RED, GREEN, GREY = "#369", "#c00", "#2a2", "#555"
TICK = 3.0  # length of a tick mark, px

#: the horizontal lines each panel draws: band bottom and top, low and high limit (None: open), nominal
Levels = tuple[float, float, float | None, float | None, float]


def render_svg(name: str, samples: Sequence[float], nominal: float, low: float | None, high: float | None,
               sample_label: str = "sample", unit: str = "ms") -> str:
    """SVG of ``samples`` in order (outside [low, high] in red) and their histogram, with the band and nominal."""
    bottom, top = band_edges(samples, nominal, low, high)
    shown = [*samples, nominal, bottom, top, *(v for v in (low, high) if v is not None)]
    y = Scale.padded(min(shown), max(shown), PLOT_BOTTOM, PLOT_TOP)
    levels = (bottom, top, low, high, nominal)
    parts = [f"<svg xmlns='http://www.w3.org/2000/svg' width='{WIDTH}' height='{HEIGHT}' "
             f"viewBox='0 0 {WIDTH} {HEIGHT}' font-family='DejaVu Sans,Arial,sans-serif' font-size='8.5'>",
             f"<title>{html.escape(name)}</title>",
             f"<rect width='{WIDTH}' height='{HEIGHT}' fill='#fff'/>",
             _text(SERIES_X[0], 15, name, "start", size=10),
             *_series_panel(samples, low, high, y, levels, sample_label),
             *_histogram_panel(samples, bottom, top, y, levels),
             *_y_axis(y, unit), "</svg>"]
    return "\n".join(parts)


def band_edges(samples: Sequence[float], nominal: float, low: float | None, high: float | None,
               ) -> tuple[float, float]:
    """The shaded band: the limits, or 10 % of the values' span beyond them where a limit is open."""
    values = [*samples, nominal, *(v for v in (low, high) if v is not None)]
    span = (max(values) - min(values)) or 1.0
    bottom = low if low is not None else min(values) - 0.1 * span
    top = high if high is not None else max(values) + 0.1 * span
    return bottom, top


def histogram_counts(samples: Sequence[float], bottom: float, top: float) -> tuple[list[float], list[int]]:
    """Bin edges and counts: HISTOGRAM_BINS bins of one width across the whole visible range, so that tight
    samples pile up into a visible bar (bins over the samples' own range would be too thin to see against the
    band). Like numpy, each bin holds [edge, next edge), the last one its upper edge too."""
    low_edge, high_edge = min([bottom, *samples]), max([top, *samples])
    edges = [low_edge + (high_edge - low_edge) * k / HISTOGRAM_BINS for k in range(HISTOGRAM_BINS + 1)]
    counts = [0] * HISTOGRAM_BINS
    width = (high_edge - low_edge) / HISTOGRAM_BINS
    for value in samples:
        index = int((value - low_edge) / width) if width > 0 else 0
        counts[min(max(index, 0), HISTOGRAM_BINS - 1)] += 1
    return edges, counts


def within(low: float | None, high: float | None, value: float) -> bool:
    return (low is None or value >= low) and (high is None or value <= high)


def _series_panel(samples: Sequence[float], low: float | None, high: float | None, y: Scale,
                  levels: Levels, sample_label: str) -> list[str]:
    """The samples in order: the line through them, a dot each (larger and red outside the band)."""
    x = Scale.padded(0, max(len(samples) - 1, 0), *SERIES_X)
    x_ticks = x.ticks(integer=True)
    points = [(x(n), y(v)) for n, v in enumerate(samples)]
    parts = _panel_background(x, y, levels, x_ticks)
    if len(points) > 1:
        coordinates = " ".join(f"{px:.1f},{py:.1f}" for px, py in points)
        parts.append(f"<polyline points='{coordinates}' fill='none' stroke='{BLUE}' stroke-width='0.9'/>")
    for (px, py), value in zip(points, samples, strict=True):
        inside = within(low, high, value)
        parts.append(f"<circle cx='{px:.1f}' cy='{py:.1f}' r='{1.4 if inside else 2.1}' "
                     f"fill='{BLUE if inside else RED}'/>")
    return [*parts, *_x_axis(x, x_ticks, f"{sample_label} #")]


def _histogram_panel(samples: Sequence[float], bottom: float, top: float, y: Scale,
                     levels: Levels) -> list[str]:
    """The samples' histogram, lying on its side against the series' y scale."""
    edges, counts = histogram_counts(samples, bottom, top)
    x = Scale(0.0, max(max(counts, default=0), 1) * (1 + 2 * 0.05), *HISTOGRAM_X)
    x_ticks = x.ticks(count=4, integer=True)
    parts = _panel_background(x, y, levels, x_ticks)
    for k, count in enumerate(counts):
        if count:
            upper, lower = y(edges[k + 1]), y(edges[k])
            parts.append(f"<rect x='{x(0):.1f}' y='{upper:.1f}' width='{x(count) - x(0):.1f}' "
                         f"height='{max(lower - upper, 0.5):.1f}' fill='{BLUE}'/>")
    return [*parts, *_x_axis(x, x_ticks, "count")]


def _panel_background(x: Scale, y: Scale, levels: Levels,
                      x_ticks: list[float]) -> list[str]:
    """The band, the light grid, the dashed limits and the nominal line across one panel."""
    bottom, top, low, high, nominal = levels
    left, right = x.start, x.end
    band_top, band_bottom = sorted((y(top), y(bottom)))
    parts = [f"<rect x='{left}' y='{band_top:.1f}' width='{right - left}' height='{band_bottom - band_top:.1f}' "
             f"fill='{GREEN}' fill-opacity='0.12'/>"]
    grid = "stroke='#000' stroke-opacity='0.12' stroke-width='0.5'"
    parts += [_line(left, y(v), right, y(v), grid) for v in y.ticks()]
    parts += [_line(x(v), PLOT_TOP, x(v), PLOT_BOTTOM, grid) for v in x_ticks]
    parts += [_line(left, y(v), right, y(v), f"stroke='{GREEN}' stroke-width='0.9' stroke-dasharray='4 2'")
              for v in (low, high) if v is not None]
    parts.append(_line(left, y(nominal), right, y(nominal), f"stroke='{GREY}' stroke-width='0.9'"))
    return parts


def _x_axis(x: Scale, ticks: list[float], label: str) -> list[str]:
    """The panel's frame, tick marks and labels below it, and the axis label."""
    left, right = x.start, x.end
    parts = [f"<rect x='{left}' y='{PLOT_TOP}' width='{right - left}' height='{PLOT_BOTTOM - PLOT_TOP}' "
             "fill='none' stroke='#000' stroke-width='0.8'/>"]
    for v, text in zip(ticks, tick_labels(ticks), strict=True):
        parts.append(_line(x(v), PLOT_BOTTOM, x(v), PLOT_BOTTOM + TICK, "stroke='#000' stroke-width='0.8'"))
        parts.append(_text(x(v), PLOT_BOTTOM + TICK + 9, text, "middle"))
    parts.append(_text((left + right) / 2, HEIGHT - 6, label, "middle", size=9))
    return parts


def _y_axis(y: Scale, unit: str) -> list[str]:
    """Tick marks and labels left of the series panel (the histogram shares them), and the unit."""
    ticks = y.ticks()
    left = SERIES_X[0]
    parts = []
    for v, text in zip(ticks, tick_labels(ticks), strict=True):
        parts.append(_line(left - TICK, y(v), left, y(v), "stroke='#000' stroke-width='0.8'"))
        parts.append(_text(left - TICK - 2, y(v) + 3, text, "end"))
    middle = (PLOT_TOP + PLOT_BOTTOM) / 2
    parts.append(f"<text x='10' y='{middle}' font-size='9' text-anchor='middle' dominant-baseline='middle' "
                 f"transform='rotate(-90 10 {middle})'>{html.escape(unit)}</text>")
    return parts


def _line(x1: float, y1: float, x2: float, y2: float, style: str) -> str:
    return f"<line x1='{x1:.1f}' y1='{y1:.1f}' x2='{x2:.1f}' y2='{y2:.1f}' {style}/>"


def _text(x: float, y: float, text: str, anchor: str, size: float | None = None) -> str:
    font = f" font-size='{size}'" if size else ""
    return f"<text x='{x:.1f}' y='{y:.1f}' text-anchor='{anchor}'{font}>{html.escape(text)}</text>"
