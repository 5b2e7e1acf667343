"""The time budget of a run: per test, the seconds owed to the device (booked by the DUT layer's waits,
``dut/link/time_budget.py``) and the rest, the tester's; per area and in total; the tests that cost most, and why.

The run's wall time is the process's (interpreter start, imports and collection included, as a user waits
for them), read from /proc on Linux, else from the session's start. ``startup_s`` is the part of it before the first
test began (interpreter, imports, option checks, collection: the tester's fixed cost; the device's own start-up
checks run in the first test's set-up, after it). ``host_wait_s`` is the time the thread that runs the tests was
ready to run but the host ran something else (Linux schedstat; None elsewhere): what a loaded host added to the wall
time, so that a run's own cost can be told from its host's load.
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from encoder_conformance.dut.link.time_budget import BUDGET, difference
from encoder_conformance.dut.link.windows import Windows
from encoder_conformance.run_summary import area_of

TOP = 10


@dataclass
class TestCost:
    nodeid: str
    seconds: float
    owed: dict[str, float]

    @property
    def tester(self) -> float:
        return max(0.0, self.seconds - sum(self.owed.values()))

    def why(self) -> str:
        parts = sorted(self.owed.items(), key=lambda item: -item[1])
        owed = ", ".join(f"{name} {seconds:.2f} s" for name, seconds in parts if seconds >= 0.005)
        return f"{owed or 'nothing owed'}; tester {self.tester:.2f} s"


@dataclass
class RunBudget:
    session_started: float = field(default_factory=time.monotonic)
    first_test_started: float | None = None  # time.monotonic() as the first test began
    tests: list[TestCost] = field(default_factory=list)
    windows: Windows | None = None  # the device's silence windows and the measurement they came from


KEY = pytest.StashKey[RunBudget]()


def _process_age_s() -> float | None:
    """Seconds since this process started (Linux /proc), None elsewhere."""
    try:
        fields = Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()
        started_ticks = int(fields[19])  # field 22 of the whole line: start time in clock ticks since boot
        uptime = float(Path("/proc/uptime").read_text().split()[0])
        return uptime - started_ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def _host_wait_s() -> float | None:
    """Seconds this thread has waited on a run queue since it started (Linux schedstat), None elsewhere."""
    try:
        return int(Path("/proc/thread-self/schedstat").read_text().split()[1]) / 1e9
    except (OSError, ValueError, IndexError):
        return None


def start(config: pytest.Config) -> None:
    config.stash[KEY] = RunBudget()


def record_windows(config: pytest.Config, windows: Windows) -> None:
    """The run's silence windows: each used window's length and source go into the budget."""
    run = config.stash.get(KEY, None)
    if run is not None:
        run.windows = windows


@contextmanager
def measure(item: pytest.Item) -> Iterator[None]:
    """Book one test's set-up, call and teardown: its seconds and what of them the device was owed."""
    run = item.config.stash.get(KEY, None)
    if run is None:
        yield
        return
    if run.first_test_started is None:
        run.first_test_started = time.monotonic()
    before, started = BUDGET.snapshot(), time.perf_counter()
    try:
        yield
    finally:
        run.tests.append(TestCost(item.nodeid, time.perf_counter() - started,
                                  difference(BUDGET.snapshot(), before)))


def budget(config: pytest.Config) -> dict[str, Any] | None:
    """The budget so far, as run-summary.json keeps it."""
    run = config.stash.get(KEY, None)
    if run is None:
        return None
    age = _process_age_s()
    wall = age if age is not None else time.monotonic() - run.session_started
    owed = {name: round(seconds, 3) for name, seconds in BUDGET.snapshot().items() if seconds > 0}
    owed_total = sum(owed.values())
    in_tests = sum(t.seconds for t in run.tests)
    first = run.first_test_started
    areas: dict[str, dict[str, float]] = {}
    for cost in run.tests:
        area = areas.setdefault(area_of(cost.nodeid), {"seconds": 0.0, "owed": 0.0, "tests": 0})
        area["seconds"] += cost.seconds
        area["owed"] += sum(cost.owed.values())
        area["tests"] += 1
    return {
        "wall_s": round(wall, 3),
        "owed_s": round(owed_total, 3),
        "owed": owed,
        "tester_s": round(wall - owed_total, 3),
        "tester_share": round((wall - owed_total) / wall, 3) if wall > 0 else None,
        "outside_tests_s": round(wall - in_tests, 3),  # start-up, collection, reports
        "startup_s": None if first is None else round(wall - (time.monotonic() - first), 3),  # to the first test
        "inside_tests_s": round(in_tests, 3),
        "host_wait_s": None if (waited := _host_wait_s()) is None else round(waited, 3),
        "tester_share_inside": round(_tester_inside(run.tests) / in_tests, 3) if in_tests > 0 else None,
        **_owed_cpu(),
        "tests": len(run.tests),
        "tester_per_test_median_ms": _median_ms([t.tester for t in run.tests]),
        "areas": {name: {key: round(value, 3) for key, value in values.items()} for name, values in areas.items()},
        "costliest": [{"nodeid": t.nodeid, "seconds": round(t.seconds, 3), "why": t.why()}
                      for t in sorted(run.tests, key=lambda t: -t.seconds)[:TOP]],
        **_windows(run.windows),
    }


def _tester_inside(tests: list[TestCost]) -> float:
    """The tester's seconds inside the tests: each test's time less what it owed the device."""
    return sum(t.tester for t in tests)


def _owed_cpu() -> dict[str, Any]:
    """Of the owed seconds, the tester process's own CPU time during them, in total and per category: owed by
    the categories' meaning, the tester's work all the same (its SDO client, receive thread, frame log)."""
    cpu = {name: round(seconds, 3) for name, seconds in BUDGET.cpu_snapshot().items() if seconds > 0}
    return {"owed_tester_cpu_s": round(sum(cpu.values()), 3), "owed_tester_cpu": cpu}


def _windows(windows: Windows | None) -> dict[str, Any]:
    """Each silence window used (name, seconds, source) and the measurement of the device's answers."""
    if windows is None:
        return {}
    return {"windows": windows.evidence(),
            "answer_times": None if windows.sdo is None else {"sdo": windows.sdo.evidence()}}


def _median_ms(values: list[float]) -> float | None:
    return round(statistics.median(values) * 1000, 2) if values else None


def terminal_line(config: pytest.Config) -> str | None:
    data = budget(config)
    if data is None or not data["tests"]:
        return None
    owed = ", ".join(f"{name} {seconds:.1f} s" for name, seconds in sorted(data["owed"].items(), key=lambda i: -i[1]))
    return (f"time budget: {data['wall_s']:.1f} s, of which owed to the device {data['owed_s']:.1f} s ({owed}); "
            f"tester {data['tester_s']:.1f} s ({100 * (data['tester_share'] or 0):.0f} %, "
            f"{data['outside_tests_s']:.1f} s outside the tests, {data['startup_s']:.1f} s to the first test, "
            f"median {data['tester_per_test_median_ms']} ms per test; "
            f"{100 * (data['tester_share_inside'] or 0):.0f} % of the time inside the tests)" + _host_wait_text(data))


#: a host wait shorter than this share of the run is a host's ordinary scheduling, not worth a word
HOST_WAIT_WORTH_SAYING = 0.05


def _host_wait_text(data: dict[str, Any]) -> str:
    """'; the host kept the tests waiting 14.0 s of it (other load on the host)' where that is a notable share."""
    waited = data.get("host_wait_s")
    if not waited or waited < HOST_WAIT_WORTH_SAYING * data["wall_s"]:
        return ""
    return f"; the host kept the tests waiting {waited:.1f} s of it (other load on the host)"
