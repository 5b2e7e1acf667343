"""The same run repeated, several at a time, optionally beside a busy process: which verdicts are stable.

A timing verdict that fails once in twenty runs of a conformant twin is the tester's problem, not
the device's. This runs the suites (or a ``-k`` selection) ``runs`` times against the twin,
``parallel`` at a time, each a separate pytest process parsed from its JUnit XML (as the fault matrix
does), and lists every test that did not pass every time. Measurements recorded as JUnit properties
(``timing <name> <figure>``, see plugin/timing_record.py) are summarised over the runs (the lowest and
highest value seen), with the limits each run reported, so the margin a timing
limit leaves on this machine can be read off.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from encoder_conformance.plugin.junit_coverage import CLASS_NAME as COVERAGE_CASE_CLASS
from encoder_conformance.runs.fault_matrix import RunResult, run_suite
from encoder_conformance.runs.host_load import busy_process

MEASUREMENT_PREFIX = "timing "
SHOWN = ("p50", "p99", "max")  # the figures the summary lists per timing measurement


@dataclass
class RepeatedRuns:
    """The outcomes of every run, and the numeric JUnit measurements per (test, name) over all runs."""

    runs: list[RunResult]
    measurements: dict[tuple[str, str], list[float]] = field(default_factory=dict)
    limits: dict[tuple[str, str], set[str]] = field(default_factory=dict)  # (test, measurement) -> bands seen
    messages: dict[str, list[str]] = field(default_factory=dict)  # test -> the first line of each failure

    def outcomes(self) -> dict[str, Counter[str]]:
        """Test -> how often it passed, failed, skipped or errored."""
        counts: dict[str, Counter[str]] = defaultdict(Counter)
        for run in self.runs:
            for test, outcome in run.outcomes.items():
                counts[test][outcome] += 1
        return counts

    def unstable(self) -> dict[str, Counter[str]]:
        """Tests that failed at least once or did not have the same outcome every time (an inconclusive skip)."""
        return {t: c for t, c in self.outcomes().items() if c["failed"] or c["error"] or len(c) > 1}

    def failing(self) -> dict[str, Counter[str]]:
        """Tests that failed or errored at least once."""
        return {t: c for t, c in self.outcomes().items() if c["failed"] or c["error"]}

    def _range(self, test: str, key: str) -> str:
        values = self.measurements.get((test, key))
        return f"{min(values):.2f}..{max(values):.2f}" if values else "-"

    def format(self) -> str:
        lines = [f"{len(self.runs)} runs: return codes {dict(Counter(r.returncode for r in self.runs))}"]
        unstable = self.unstable()
        lines.append(f"tests that failed at least once: {len(self.failing())}; not the same outcome every time: "
                     f"{len(unstable)}")
        for test, counts in sorted(unstable.items()):
            lines.append(f"  {test}: {dict(counts)}")
            lines += [f"      {message}" for message in self.messages.get(test, [])[:3]]
        if self.measurements:
            lines.append("timing over all runs (lowest..highest of each run's figure), against the limits:")
            for test, name in sorted({(t, n.rsplit(" ", 1)[0]) for t, n in self.measurements}):
                figures = [f"{figure} {self._range(test, f'{name} {figure}_ms')}" for figure in SHOWN]
                bands = " | ".join(sorted(self.limits.get((test, f"{name} limits_ms"), set()))) or "none"
                lines.append(f"  {test}: {name}: {', '.join(figures)} ms; limits {bands}")
        return "\n".join(lines)


def _measurements(junit: Path) -> dict[tuple[str, str], float | str]:
    """``timing`` properties of every test case in one JUnit file: numbers as float, the rest (limit bands,
    the clock) as text."""
    found: dict[tuple[str, str], float | str] = {}
    if not junit.exists():
        return found
    for case in ET.parse(junit).getroot().iter("testcase"):
        test = f"{case.get('classname', '').split('.')[-1]}::{case.get('name')}"
        for prop in case.iter("property"):
            name, value = prop.get("name", ""), prop.get("value", "")
            if name.startswith(MEASUREMENT_PREFIX):
                key = (test, name.removeprefix(MEASUREMENT_PREFIX))
                try:
                    found[key] = float(value)
                except ValueError:
                    found[key] = value
    return found


def _failure_messages(junit: Path) -> dict[str, str]:
    """Test -> the first line of its failure or error message, in one JUnit file."""
    found: dict[str, str] = {}
    if not junit.exists():
        return found
    for case in ET.parse(junit).getroot().iter("testcase"):
        problem = case.find("failure") if case.find("failure") is not None else case.find("error")
        if problem is not None and case.get("classname") != COVERAGE_CASE_CLASS:  # the run's coverage: no test
            test = f"{case.get('classname', '').split('.')[-1]}::{case.get('name')}"
            text = (problem.get("message") or problem.text or "").strip()
            found[test] = text.splitlines()[0][:300] if text else "(no message)"
    return found


def repeat_runs(profile: str, runs: int, workdir: Path, select: str | None = None, parallel: int = 2,
                busy: bool = False, variant: str | None = None) -> RepeatedRuns:
    """``runs`` runs of the suites against the ``profile`` twin (playing ``variant``, a conformant reading),
    ``parallel`` at a time (``busy``: beside a process keeping one core busy)."""

    def one(number: int) -> tuple[RunResult, dict[tuple[str, str], float | str], dict[str, str]]:
        folder = workdir / f"run-{number:02d}"
        result = run_suite(profile, variant, folder, select)
        junit = folder / (variant or "no-fault") / "junit.xml"
        return result, _measurements(junit), _failure_messages(junit)

    collected = RepeatedRuns([])
    values: dict[tuple[str, str], list[float]] = defaultdict(list)
    limits: dict[tuple[str, str], set[str]] = defaultdict(set)
    with busy_process(busy), ThreadPoolExecutor(max_workers=parallel) as pool:
        for result, found, messages in pool.map(one, range(runs)):
            collected.runs.append(result)
            for test, message in messages.items():
                collected.messages.setdefault(test, []).append(message)
            for key, value in found.items():
                if isinstance(value, float):
                    values[key].append(value)
                elif key[1].endswith(("limits_ms", "limits")):
                    limits[key].add(value)
    collected.measurements, collected.limits = dict(values), dict(limits)
    return collected
