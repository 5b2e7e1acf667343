"""One pytest session of suites/ in its own process, for self-tests that judge a whole run (shared helper).

``FullRuns``: the full suites against a profile's fault-free twin, run once per self-test session and shared by
every module that judges that run (test_twins, the fault matrix's baseline, the usual order of
test_shuffled_order): each asserted what it asserts on its own run of the same command before.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from encoder_conformance.runs.fault_matrix import matrix_env
from encoder_conformance.runs.suite_runner import SessionResult, run_pytest

REPO = Path(__file__).resolve().parents[1]

#: suite runs at a time on two cores. A run mostly waits for its twin (a WDGA run: ~5 s of CPU in 17 s; with four
#: at a time the machine was 57 % idle on average over the twins, EDS, variant and fault matrices). Before the
#: twin was forked from its run (sim/forked.py), every twin start was a 0.3 s burst of imports, and with three runs
#: at a time a twin was sometimes stalled past its heartbeat tolerance (seen: a 40 ms late heartbeat).
#: The full twin runs take the same number: they idle through the POSITAL's boot-ups and the SIKO's execution
#: times, yet six at a time stalled the host in one CI run of three (SDO answers reached the tester 400 ms late)
PARALLEL_RUNS = 4


def run_suite(tmp_path: Path, *args: str, env: dict[str, str] | None = None) -> tuple[SessionResult, float]:
    """One pytest session of suites/ in its own process (forked from the pre-loaded server, suite_runner)."""
    command = [str(REPO / "suites"), "-q", "-p", "no:cacheprovider", "--tb=line", "--ec-report-dir",
               str(tmp_path / "report"), *args]
    start = time.monotonic()
    completed = run_pytest(command, REPO, tmp_path / "pytest-output.txt", timeout=600, env=env)
    return completed, time.monotonic() - start


@dataclass(frozen=True)
class FullRun:
    """A full run: its folder (the report in ``folder / "report"``), how it ended, and its wall time."""

    folder: Path
    completed: SessionResult
    seconds: float


class FullRuns:
    """The full suites against each profile's fault-free twin, once per self-test session (thread-safe: the
    matrices ask from their worker threads). The environment is the fault matrix's (no CAN_* settings, hypothesis
    derandomized), so that every module judges the same examples."""

    def __init__(self, mktemp: Callable[[str], Path]):
        self._mktemp = mktemp
        self._runs: dict[str, FullRun] = {}
        self._locks: dict[str, threading.Lock] = {}
        self._guard = threading.Lock()

    def __call__(self, profile: str) -> FullRun:
        with self._guard:
            lock = self._locks.setdefault(profile, threading.Lock())
        with lock:
            if profile not in self._runs:
                folder = self._mktemp(Path(profile).stem)
                completed, seconds = run_suite(folder, "--ec-profile", profile, env=matrix_env())
                self._runs[profile] = FullRun(folder, completed, seconds)
            return self._runs[profile]
