"""One pytest session of suites/ in its own process, for self-tests that judge a whole run (shared helper)."""

from __future__ import annotations

import time
from pathlib import Path

from encoder_conformance.runs.suite_runner import SessionResult, run_pytest

REPO = Path(__file__).resolve().parents[1]

#: suite runs at a time on two cores. A run mostly waits for its twin (a WDGA run: ~5 s of CPU in 17 s; with four
#: at a time the machine was 57 % idle on average over the twins, EDS, variant and fault matrices). Before the
#: twin was forked from its run (sim/forked.py), every twin start was a 0.3 s burst of imports, and with three runs
#: at a time a twin was sometimes stalled past its heartbeat tolerance (seen: a 40 ms late heartbeat).
#: The full twin runs take the same number: they idle through the POSITAL's boot-ups and the SIKO's execution
#: times, yet six at a time stalled the host in one CI run of three (SDO answers reached the tester 400 ms late)
PARALLEL_RUNS = 4


def run_suite(tmp_path: Path, *args: str) -> tuple[SessionResult, float]:
    """One pytest session of suites/ in its own process (forked from the pre-loaded server, suite_runner)."""
    command = [str(REPO / "suites"), "-q", "-p", "no:cacheprovider", "--tb=line", "--ec-report-dir",
               str(tmp_path / "report"), *args]
    start = time.monotonic()
    completed = run_pytest(command, REPO, tmp_path / "pytest-output.txt", timeout=600)
    return completed, time.monotonic() - start
