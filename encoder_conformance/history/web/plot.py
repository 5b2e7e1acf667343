"""The page's plots as small inline SVG (no JavaScript, no plotting library): pass rate and the areas that fail
most per station or profile, and one serial number's runs on a time axis. Every text is escaped."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime

from markupsafe import Markup, escape

COLOURS = {"PASS": "#2e7d32", "PASS WITH WARNINGS": "#c98a00", "INCOMPLETE": "#ad4e00", "FAIL": "#c62828",
           "COULD NOT TEST": "#6d6d6d", "INTERNAL ERROR": "#6a1b9a", "NOT RUN": "#9e9e9e"}
_ROW = 26
_LABEL_W = 230
_BAR_W = 200
_RATE_W = 100
_AREA_W = 440
_AREA_MAX_BAR = 50
_CHAR_W = 6.8  # an average character at 12 px


@dataclass
class Group:
    """One station's or profile's runs: how many, how many passed, the areas that failed most."""

    name: str
    runs: int
    passed: int
    failing: list[tuple[str, int]] = field(default_factory=list)  # (area, failed runs), most first

    @property
    def rate(self) -> float:
        return self.passed / self.runs if self.runs else 0.0


def _text(x: float, y: float, text: str, anchor: str = "start", cls: str = "") -> str:
    css = f' class="{cls}"' if cls else ""
    return f'<text x="{x:.1f}" y="{y:.1f}" text-anchor="{anchor}"{css}>{escape(text)}</text>'


def _short(text: str, length: int = 32) -> str:
    return text if len(text) <= length else text[: length - 1] + "…"


def group_plot(groups: Sequence[Group], title: str) -> Markup:
    """Per group: a bar of its pass rate (green passed, red the rest), the rate, and bars of the areas that failed
    in most of its runs (as many as fit)."""
    height = 34 + _ROW * max(len(groups), 1)
    width = _LABEL_W + _BAR_W + _RATE_W + _AREA_W
    areas_x = _LABEL_W + _BAR_W + _RATE_W
    most = max((count for g in groups for _, count in g.failing[:1]), default=1)
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" class="plot" width="{width}" height="{height}" '
             f'viewBox="0 0 {width} {height}" role="img" aria-label="{escape(title)}">',
             f"<title>{escape(title)}</title>",
             _text(_LABEL_W, 14, "pass rate", cls="head"),
             _text(areas_x, 14, "areas that fail most (failed runs)", cls="head")]
    for n, group in enumerate(groups):
        y = 26 + n * _ROW
        parts += [
            _text(_LABEL_W - 8, y + 13, _short(group.name or "(none)"), anchor="end"),
            f'<rect x="{_LABEL_W}" y="{y}" width="{_BAR_W}" height="18" fill="{COLOURS["FAIL"]}" opacity="0.75"/>',
            f'<rect x="{_LABEL_W}" y="{y}" width="{_BAR_W * group.rate:.1f}" height="18" fill="{COLOURS["PASS"]}"/>',
            _text(_LABEL_W + _BAR_W + 8, y + 13, f"{group.rate:.0%} of {group.runs}"),
        ]
        x: float = areas_x
        for area, count in group.failing:
            label = f"{area} ({count})"
            bar = max(4.0, _AREA_MAX_BAR * count / most)
            if x + bar + 4 + _CHAR_W * len(label) > width:
                break
            parts.append(f'<rect x="{x:.1f}" y="{y + 3}" width="{bar:.1f}" height="12" fill="{COLOURS["FAIL"]}"/>')
            parts.append(_text(x + bar + 4, y + 13, label))
            x += bar + 14 + _CHAR_W * len(label)
        if not group.failing:
            parts.append(_text(x, y + 13, "none failed", cls="muted"))
    if not groups:
        parts.append(_text(_LABEL_W, 40, "no run matches", cls="muted"))
    parts.append("</svg>")
    return Markup("".join(parts))


def timeline_plot(runs: Sequence[dict[str, object]], width: int = 900) -> Markup:
    """One dot per run on a time axis, coloured by verdict, each a link to the run's page."""
    height = 70
    moments = [datetime.fromisoformat(str(run["started_utc"])) for run in runs]
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" class="plot" width="{width}" height="{height}" '
             f'viewBox="0 0 {width} {height}" role="img" aria-label="runs over time">',
             f'<line x1="20" y1="35" x2="{width - 20}" y2="35" stroke="#888"/>']
    if moments:
        first, last = min(moments), max(moments)
        span = (last - first).total_seconds() or 1.0
        for run, moment in zip(runs, moments, strict=True):
            x = 30 + (width - 60) * ((moment - first).total_seconds() / span if len(runs) > 1 else 0.5)
            colour = COLOURS.get(str(run["overall"]), "#000")
            label = f"run {run['id']}: {run['overall']} ({str(run['started'])[:16]})"
            parts.append(f'<a href="/run/{int(str(run["id"]))}"><circle cx="{x:.1f}" cy="35" r="8" fill="{colour}">'
                         f"<title>{escape(label)}</title></circle></a>")
        parts += [_text(20, 62, str(runs[0]["started"])[:10]),
                  _text(width - 20, 62, str(runs[-1]["started"])[:10], anchor="end")]
    parts.append("</svg>")
    return Markup("".join(parts))
