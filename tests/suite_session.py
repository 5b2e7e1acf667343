"""One pytest session of suites/ in its own process, for self-tests that judge a whole run (shared helper)."""

from __future__ import annotations

import time
from pathlib import Path

from encoder_conformance.runs.suite_runner import SessionResult, run_pytest

REPO = Path(__file__).resolve().parents[1]

#: suite runs at a time on two cores. A run mostly waits for its twin (a WDGA run: ~5 s of CPU in 17 s; with four
#: at a time the machine was 57 % idle on average over the twins, EDS, variant and fault matrices). Before the
#: twin was forked from its run (sim/forked.py), every twin start was a 0.3 s burst of imports, and with three runs
#: at a time a twin was sometimes stalled past its heartbeat tolerance (seen: a 40 ms late heartbeat)
PARALLEL_RUNS = 4
#: full runs against the shipped twins: half of their time is the POSITAL's 4 s boot-ups and the SIKO's execution
#: times, spent idle. Six at a time passed in two CI runs of three; in the third, two runs' SDO answers reached the
#: tester 400 ms after the twin sent them (a host stall), and two WayCon twins failed: four, as the others
FULL_RUN_PARALLEL = 4


def run_suite(tmp_path: Path, *args: str) -> tuple[SessionResult, float]:
    """One pytest session of suites/ in its own process (forked from the pre-loaded server, suite_runner)."""
    command = [str(REPO / "suites"), "-q", "-p", "no:cacheprovider", "--tb=line", "--report-dir",
               str(tmp_path / "report"), *args]
    start = time.monotonic()
    completed = run_pytest(command, REPO, tmp_path / "pytest-output.txt", timeout=600)
    return completed, time.monotonic() - start
