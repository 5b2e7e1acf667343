"""A timing measurement as data: the samples, the nominal value, the limit band, the clock that stamped
them and what the limits rest on. The report shows its statistics and plot; JUnit gets the figures as
properties, allure the plot and the samples as CSV (see reporting.attach_evidence, fixtures/evidence.py)."""

from __future__ import annotations

import html
from dataclasses import dataclass, field

from encoder_conformance.models.timing import TimingSummary
from encoder_conformance.plugin.timing_plot import render_svg

#: the figures each timing test gives JUnit (as properties "timing <name> <figure>_ms") and the report table
REPORTED = ("mean", "p50", "p95", "p99", "max")


@dataclass
class TimingMeasurement:
    """Samples in ms (intervals or latencies) against ``nominal`` and the band [``low``, ``high``] (either may
    be None: open). ``judged`` says what the verdict compares with the band (every sample, the fitted
    period, ...); samples outside the band are not a failure where the verdict is judged otherwise."""

    name: str
    samples: tuple[float, ...]
    nominal: float
    low: float | None
    high: float | None
    clock: str
    basis: str
    judged: str
    sample_label: str = "interval"  # what one sample is, for the plot's axis and the CSV
    unit: str = "ms"
    _svg: str | None = field(default=None, repr=False)

    @property
    def summary(self) -> TimingSummary:
        return TimingSummary.of(self.samples, self.nominal)

    def outside(self) -> int:
        """How many samples lie outside the band."""
        return sum(1 for s in self.samples if (self.low is not None and s < self.low)
                   or (self.high is not None and s > self.high))

    def band(self) -> str:
        low = "" if self.low is None else f"{self.low:.2f}"
        high = "" if self.high is None else f"{self.high:.2f}"
        return f"[{low} .. {high}] {self.unit}"

    def properties(self) -> list[tuple[str, str]]:
        """(name, value) pairs for JUnit: the figures, the band and the clock."""
        summary = self.summary
        figures = summary.figures()
        props = [(f"timing {self.name} count", str(summary.count)),
                 (f"timing {self.name} nominal_{self.unit}", f"{self.nominal:g}")]
        props += [(f"timing {self.name} {key}_{self.unit}", f"{figures[key]:.3f}") for key in REPORTED]
        props += [(f"timing {self.name} limits_{self.unit}", self.band()), (f"timing {self.name} clock", self.clock)]
        return props

    def csv(self) -> str:
        return f"n,{self.sample_label}_{self.unit}\n" + "\n".join(f"{n},{v:.3f}" for n, v in enumerate(self.samples))

    def svg(self) -> str:
        """The plot as SVG markup (rendered once: the HTML report and allure may both ask for it)."""
        if self._svg is None:
            self._svg = render_svg(self.name, self.samples, self.nominal, self.low, self.high, self.sample_label,
                                   self.unit)
        return self._svg

    def html_table(self) -> str:
        summary = self.summary
        figures = summary.figures()
        head = "".join(f"<th>{key}</th>" for key in ("n", *REPORTED, "nominal", "limits"))
        cells = "".join(f"<td>{figures[key]:.2f}</td>" for key in REPORTED)
        return (f"<table class='timing'><caption>{html.escape(self.name)} ({self.unit})</caption>"
                f"<tr>{head}</tr><tr><td>{summary.count}</td>{cells}<td>{self.nominal:g}</td>"
                f"<td>{html.escape(self.band())}</td></tr></table>"
                f"<div>judged: {html.escape(self.judged)}; {self.outside()} of {summary.count} samples outside "
                f"the band</div><div>limits rest on: {html.escape(self.basis)}</div>"
                f"<div>clock: {html.escape(self.clock)}</div>")
