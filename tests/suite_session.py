"""One pytest session of suites/ in its own process, for self-tests that judge a whole run (shared helper)."""

from __future__ import annotations

import time
from pathlib import Path

from encoder_conformance.runs.suite_runner import SessionResult, run_pytest

REPO = Path(__file__).resolve().parents[1]

#: two runs at a time on two cores: with three, a twin itself (the device side) is sometimes stalled past its
#: heartbeat tolerance (seen: a 40 ms late heartbeat and event-timer frame at once, in an EDS-draft twin)
PARALLEL_RUNS = 3


def run_suite(tmp_path: Path, *args: str) -> tuple[SessionResult, float]:
    """One pytest session of suites/ in its own process (forked from the pre-loaded server, suite_runner)."""
    command = [str(REPO / "suites"), "-q", "-p", "no:cacheprovider", "--tb=line", "--report-dir",
               str(tmp_path / "report"), *args]
    start = time.monotonic()
    completed = run_pytest(command, REPO, tmp_path / "pytest-output.txt", timeout=600)
    return completed, time.monotonic() - start
