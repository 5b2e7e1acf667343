"""Per-test evidence: measurements with limits, documented deviations, notes, the bus trace, and what
the verdict rests on (a CiA clause, the device's manual, or our own inference)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from encoder_conformance.basis import BASES, Basis
from encoder_conformance.plugin.bus_trace import BusTrace
from encoder_conformance.plugin.timing_record import TimingMeasurement

__all__ = ["BASES", "EVIDENCE", "Basis", "Evidence", "InferredProblem", "Measurement", "TimingMeasurement"]


@dataclass(frozen=True)
class Measurement:
    """A value with its limits and verdict (as OpenHTF's measurements)."""

    name: str
    value: float
    unit: str
    low: float | None
    high: float | None

    @property
    def passed(self) -> bool:
        if math.isnan(self.value):
            return False
        return (self.low is None or self.value >= self.low) and (self.high is None or self.value <= self.high)

    def describe(self) -> str:
        limits = f"[{'' if self.low is None else f'{self.low:g}'} .. {'' if self.high is None else f'{self.high:g}'}]"
        return f"{self.name} = {self.value:g} {self.unit} {limits} {'PASS' if self.passed else 'FAIL'}"




@dataclass(frozen=True)
class InferredProblem:
    """What the device did against a rule that no CiA text or manual states: our reading of silence."""

    observation: str
    rests_on: str  # the profile key and the reading it holds, e.g. "capabilities.tpdo_transmission_types ..."

    def describe(self) -> str:
        return f"{self.observation} [inferred: {self.rests_on}]"


@dataclass
class Evidence:
    """Collected while a test runs; written to the reports by the makereport hook."""

    spec: str | None = None
    measurements: list[Measurement] = field(default_factory=list)
    deviations: list[tuple[str, str]] = field(default_factory=list)  # (quirk id, text)
    notes: list[str] = field(default_factory=list)
    trace_path: Path | None = None  # where the test's trace goes if kept (traces/<test>.asc, and .log)
    trace: BusTrace | None = None  # its frames, until the verdict decides (reporting.settle_trace)
    keep_trace: bool = False  # kept under --trace failed: the test failed or warned, or other verdicts rest on it
    basis: Basis | None = None  # set where a test knows better than its spec marker (see verdict_basis)
    basis_source: str | None = None  # the clause or manual section the verdict rests on
    inferred: list[InferredProblem] = field(default_factory=list)
    timings: list[TimingMeasurement] = field(default_factory=list)

    def measure(self, name: str, value: float, unit: str, low: float | None = None,
                high: float | None = None) -> Measurement:
        measurement = Measurement(name, value, unit, low, high)
        self.measurements.append(measurement)
        return measurement

    def timing(self, name: str, samples_ms: list[float] | tuple[float, ...], *, nominal_ms: float,
               low_ms: float | None, high_ms: float | None, clock: str, basis: str, judged: str,
               sample_label: str = "interval") -> TimingMeasurement:
        """A named timing measurement (intervals or latencies in ms) with its band, the clock that stamped the
        frames and what the limits rest on: shown in the report as statistics and a plot."""
        record = TimingMeasurement(name, tuple(samples_ms), nominal_ms, low_ms, high_ms, clock, basis, judged,
                                   sample_label)
        self.timings.append(record)
        return record

    def deviation(self, quirk_id: str, text: str) -> None:
        """The verdict relies on a documented deviation of the device (a profile quirk)."""
        self.deviations.append((quirk_id, text))

    def note(self, text: str) -> None:
        self.notes.append(text)

    def rests_on(self, basis: Basis, source: str) -> None:
        """The verdict rests on ``source`` (a CiA clause or a manual section), of kind ``basis``."""
        self.basis, self.basis_source = basis, source

    def inferred_problem(self, observation: str, rests_on: str) -> None:
        """A deviation from a rule we inferred: a warning by default, a failure with --strict."""
        self.inferred.append(InferredProblem(observation, rests_on))

    def verdict_basis(self, hard_failure: bool = False) -> Basis:
        """What the verdict rests on: our inference where only an inferred rule was broken; else the device's
        manual where a documented deviation or a manual fact decided it; else the CiA clause of the spec marker."""
        if self.inferred and not hard_failure:
            return "inferred"
        if self.basis is not None:
            return self.basis
        if self.deviations or not (self.spec or "").startswith("CiA"):
            return "manual"
        return "cia"


EVIDENCE = pytest.StashKey[Evidence]()
