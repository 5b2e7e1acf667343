"""Run the suites against the simulator once per named fault and tabulate which tests catch which fault.

A conformance test that no fault can make fail proves nothing; the matrix shows it. Each run
is a separate pytest session in its own process (the same session a user's command runs; forked from a
pre-loaded server, ``suite_runner``), parsed from its JUnit XML. A fault
the suites can only see through a rule they infer (``fault_catalogue.JUDGED_STRICTLY``) runs with
``--ec-strict``, so that its broken rule fails instead of warning; every other run (and the
baseline) is judged as a user's run is.
"""

from __future__ import annotations

import json
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path

from encoder_conformance.paths import CONTENT_ROOT, SUITES_DIR
from encoder_conformance.plugin.hypothesis_profiles import PROFILE_ENV as HYPOTHESIS_PROFILE_ENV
from encoder_conformance.plugin.junit_coverage import CLASS_NAME as COVERAGE_CASE_CLASS
from encoder_conformance.plugin.verdicts import STRICT_OPTION
from encoder_conformance.runs.suite_runner import SessionResult, run_pytest
from encoder_conformance.sim.fault_catalogue import JUDGED_STRICTLY, TARGET_MODULES

_ENTRY_PARAM = re.compile(r"\[0x[0-9A-F]{4}\.[0-9A-F]{2} .*\]$")  # names may hold brackets: "Kv [1/s]"


def test_key(name: str) -> str:
    """Group per-entry parametrisations under their test function; keep fixed parameters apart."""
    return _ENTRY_PARAM.sub("[each entry]", name)


@dataclass
class RunResult:
    fault: str | None
    returncode: int
    outcomes: dict[str, str] = field(default_factory=dict)  # test name -> passed/failed/skipped/error

    def keys_with(self, outcome: str) -> set[str]:
        return {test_key(n) for n, o in self.outcomes.items() if o == outcome}


def _parse_junit(path: Path) -> dict[str, str]:
    outcomes: dict[str, str] = {}
    for case in ET.parse(path).getroot().iter("testcase"):
        if case.get("classname") == COVERAGE_CASE_CLASS:  # the run's coverage, not a test (plugin/junit_coverage.py)
            continue
        name = f"{case.get('classname', '').split('.')[-1]}::{case.get('name')}"
        verdicts = {p.get("value") for p in case.iter("property") if p.get("name") == "verdict"}
        if "internal error" in verdicts:  # our own code broke: it catches no fault, and fails every baseline
            outcomes[name] = "internal"
        elif case.find("failure") is not None:
            outcomes[name] = "failed"
        elif case.find("error") is not None:
            outcomes[name] = "error"
        elif case.find("skipped") is not None:
            outcomes[name] = "skipped"
        else:
            outcomes[name] = "passed"
    return outcomes


#: the run's start-up check (node answers, identity matches) as a row of the matrix: a fault can make it fail
PREFLIGHT = "pre-flight::start-up check"


def _preflight_outcome(folder: Path) -> str:
    """'failed' when the run stopped at its start-up check (run-outcome.json), else 'passed'."""
    path = folder / "run-outcome.json"
    if not path.exists():
        return "passed"
    stopped = json.loads(path.read_text(encoding="utf-8")).get("stopped") or ""
    return "failed" if stopped.startswith("start-up check failed") else "passed"


def _suite_paths(faults: tuple[str, ...], targeted: bool) -> list[str]:
    """suites/ as a whole, or only the modules ``faults`` are made for (each module once, in the order named)."""
    if targeted and faults:
        modules = dict.fromkeys(module for fault in faults for module in TARGET_MODULES[fault])
        return [str(SUITES_DIR / f"{module}.py") for module in modules]
    return [str(SUITES_DIR)]


def matrix_env() -> dict[str, str]:
    """A matrix session's environment: no CAN_* settings of the caller's (the twin is the device), hypothesis
    derandomized unless set (the same fuzz examples in every matrix)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
    env.setdefault(HYPOTHESIS_PROFILE_ENV, "ci")
    return env


def run_suite(profile: str, fault: str | None, workdir: Path, select: str | None = None,
              targeted: bool = False, together: tuple[str, ...] = ()) -> RunResult:
    """One pytest run of suites/ (``targeted``: the fault's own modules) against the twin with ``fault``
    (strict about inferred rules where the fault is in JUDGED_STRICTLY). ``together``: further deviations the
    twin plays in the same run (the variant matrix's conformant variants; their modules are run too)."""
    folder, completed, command = run_session(profile, fault, workdir, select, targeted, together)
    return read_run(fault, folder, completed, select, command)


def run_session(profile: str, fault: str | None, workdir: Path, select: str | None = None,
                targeted: bool = False, together: tuple[str, ...] = ()) -> tuple[Path, SessionResult, str]:
    """run_suite's session, not read yet: its report folder, how it ended and its command line."""
    faults = (fault, *together) if fault else together
    folder = workdir / (f"{faults[0]}+{len(together)}" if together else fault or "no-fault")
    command = [*_suite_paths(faults, targeted), "-q", "-p", "no:cacheprovider",
               "--ec-profile", profile, "--ec-report-dir", str(folder), "--tb=no",
               "--ec-history", "off"]  # a fault's run says nothing about a device: not in the history
    for name in faults:
        command += ["--ec-sim-fault", name]
    if set(faults) & JUDGED_STRICTLY:
        command.append(STRICT_OPTION)
    if select:
        command += ["-k", select]
    completed = run_pytest(command, CONTENT_ROOT, folder / "pytest-output.txt", timeout=600, env=matrix_env())
    return folder, completed, " ".join(command)


def read_run(fault: str | None, folder: Path, completed: SessionResult, select: str | None = None,
             command: str = "") -> RunResult:
    """The outcomes of a finished session whose report folder is ``folder`` (its JUnit file and run outcome)."""
    junit = folder / "junit.xml"
    outcomes = _parse_junit(junit) if junit.exists() else {}
    preflight = _preflight_outcome(folder)
    if preflight == "failed" or select is None:  # a run limited by -k does not claim the start-up check
        outcomes[PREFLIGHT] = preflight
    if not outcomes or outcomes == {PREFLIGHT: "passed"}:
        raise RuntimeError(f"no results from pytest {command or folder}:\n{completed.output[-6000:]}")
    return RunResult(fault, completed.returncode, outcomes)


def run_matrix(profile: str, faults: list[str], workdir: Path, select: str | None = None,
               workers: int = 2, targeted: bool = False,
               baseline_run: Callable[[], RunResult] | None = None,
               fault_run: Callable[[str], RunResult] | None = None) -> tuple[RunResult, list[RunResult]]:
    """The fault-free baseline plus one run per fault (``workers`` runs in parallel; the baseline is one of
    them, not a run before the others).

    ``targeted``: each fault runs only against the suite modules it is made for (the baseline
    still runs everything), which proves the same two things at a fraction of the time. ``baseline_run``: where
    the caller has the fault-free run already (or shares it with others), what gives it instead of a run here;
    ``fault_run``: likewise a fault's run (the same command as here).
    """
    with ThreadPoolExecutor(max_workers=workers) as pool:
        baseline = pool.submit(baseline_run or (lambda: run_suite(profile, None, workdir, select)))
        results = list(pool.map(fault_run or (lambda f: run_suite(profile, f, workdir, select, targeted)), faults))
        return baseline.result(), results


def run_until_caught(profile: str, faults: list[str], workdir: Path, select: str | None = None,
                     workers: int = 2, must_try: frozenset[str] = frozenset(),
                     targeted: bool = False) -> tuple[RunResult, list[RunResult]]:
    """Like run_matrix, but stop once every passing test has failed under some fault.

    ``faults`` is tried in order, ``workers`` at a time: a new run starts as soon as one ends (no run waits
    for a slower one beside it); faults in ``must_try`` always run.
    """
    baseline = run_suite(profile, None, workdir, select)
    tests = baseline.keys_with("passed")
    if targeted:  # a fault made for other modules cannot catch these tests (and would collect nothing)
        modules = {test.split("::")[0] for test in tests}
        faults = [f for f in faults if modules & set(TARGET_MODULES[f])]
        must_try = must_try & frozenset(faults)
    results: list[RunResult] = []
    waiting = list(faults)
    running: set[Future[RunResult]] = set()

    def done() -> bool:
        caught = set().union(*(r.keys_with("failed") | r.keys_with("error") for r in results))
        return tests <= caught and must_try <= {r.fault for r in results}

    with ThreadPoolExecutor(max_workers=workers) as pool:
        while waiting or running:
            while waiting and len(running) < workers and not done():
                fault = waiting.pop(0)
                running.add(pool.submit(run_suite, profile, fault, workdir, select, targeted))
            if not running:
                break
            finished, running = wait(running, return_when=FIRST_COMPLETED)
            results += [future.result() for future in finished]

    def tried(result: RunResult) -> int:
        assert result.fault is not None  # every run here was started with a fault
        return faults.index(result.fault)

    return baseline, _as_if_one_at_a_time(sorted(results, key=tried), tests, must_try)


def _as_if_one_at_a_time(results: list[RunResult], tests: set[str], must_try: frozenset[str]) -> list[RunResult]:
    """The runs, in the order tried, up to where one worker would have stopped: runs started beside the one that
    completed the matrix are dropped, so that the matrix is the same whatever the number of workers."""
    caught: set[str] = set()
    tried: set[str | None] = set()
    for count, result in enumerate(results, start=1):
        caught |= result.keys_with("failed") | result.keys_with("error")
        tried.add(result.fault)
        if tests <= caught and must_try <= tried:
            return results[:count]
    return results


def format_matrix(baseline: RunResult, results: list[RunResult]) -> str:
    """Text table: one row per test, the faults that make it fail."""
    tests = sorted(baseline.keys_with("passed"))
    lines = [f"fault matrix ({len(results)} faults x {len(tests)} tests passing without faults)"]
    for test in tests:
        catching = [r.fault for r in results if test in r.keys_with("failed") | r.keys_with("error")]
        lines.append(f"  {test:90s} {', '.join(c for c in catching if c) or '** NO FAULT MAKES IT FAIL **'}")
    lines.append("faults -> number of tests they make fail:")
    for result in results:
        failing = result.keys_with("failed") | result.keys_with("error")
        lines.append(f"  {result.fault:32s} {len(failing)}")
    return "\n".join(lines)
