"""One pytest session of suites/ in its own process, for self-tests that judge a whole run (shared helper).

``FullRuns``: the full suites against a profile's fault-free twin, run once per self-test session and shared by
every module that judges that run (test_twins, the fault matrix's baseline, the usual order of
test_shuffled_order): each asserted what it asserts on its own run of the same command before. ``FaultRuns``:
likewise a fault's targeted run (the fault matrix's, which test_inferred_walk reads for the strictly judged
faults' --strict-inferred runs).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Generic, TypeVar

from encoder_conformance.runs.fault_matrix import matrix_env, run_session
from encoder_conformance.runs.session_slots import SESSION_SLOTS
from encoder_conformance.runs.suite_runner import SessionResult, run_pytest

REPO = Path(__file__).resolve().parents[1]
K = TypeVar("K")
V = TypeVar("V")

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


class _Once(Generic[K, V]):
    """Results made once per key, thread-safe (the matrices ask from their worker threads)."""

    def __init__(self, mktemp: Callable[[str], Path]):
        self._mktemp = mktemp
        self._done: dict[K, V] = {}
        self._locks: dict[K, threading.Lock] = {}
        self._guard = threading.Lock()

    def _once(self, key: K, make: Callable[[], V]) -> V:
        with self._guard:
            lock = self._locks.setdefault(key, threading.Lock())
        if not lock.acquire(blocking=False):
            # another thread makes it (a background one, maybe waiting for a slot the foreground reserved): while
            # the foreground waits for it, reservations do not hold (runs/session_slots.py: else a deadlock)
            with SESSION_SLOTS.depending():
                lock.acquire()
        try:
            if key not in self._done:
                self._done[key] = make()
            return self._done[key]
        finally:
            lock.release()


class FullRuns(_Once[str, FullRun]):
    """The full suites against each profile's fault-free twin, once per self-test session. The environment is
    the fault matrix's (no CAN_* settings, hypothesis derandomized), so that every module judges the same
    examples."""

    def __call__(self, profile: str) -> FullRun:
        def make() -> FullRun:
            folder = self._mktemp(Path(profile).stem)
            completed, seconds = run_suite(folder, "--ec-profile", profile, env=matrix_env())
            return FullRun(folder, completed, seconds)

        return self._once(profile, make)


class FaultRuns(_Once[tuple[str, str], tuple[Path, SessionResult]]):
    """A fault's targeted run against a profile's twin (runs.fault_matrix.run_session: the fault's suite modules,
    --strict-inferred where the catalogue judges it strictly), once per self-test session: (report folder, how
    the session ended)."""

    def __call__(self, profile: str, fault: str) -> tuple[Path, SessionResult]:
        def make() -> tuple[Path, SessionResult]:
            folder, completed, _ = run_session(profile, fault, self._mktemp(f"{Path(profile).stem}-{fault}"),
                                               targeted=True)
            return folder, completed

        return self._once((profile, fault), make)
