"""Per-test evidence: measurements with limits, documented deviations, notes, the bus trace."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import pytest


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


@dataclass
class Evidence:
    """Collected while a test runs; written to the reports by the makereport hook."""

    spec: str | None = None
    measurements: list[Measurement] = field(default_factory=list)
    deviations: list[tuple[str, str]] = field(default_factory=list)  # (quirk id, text)
    notes: list[str] = field(default_factory=list)
    trace_path: Path | None = None

    def measure(self, name: str, value: float, unit: str, low: float | None = None,
                high: float | None = None) -> Measurement:
        measurement = Measurement(name, value, unit, low, high)
        self.measurements.append(measurement)
        return measurement

    def deviation(self, quirk_id: str, text: str) -> None:
        """The verdict relies on a documented deviation of the device (a profile quirk)."""
        self.deviations.append((quirk_id, text))

    def note(self, text: str) -> None:
        self.notes.append(text)


EVIDENCE = pytest.StashKey[Evidence]()
