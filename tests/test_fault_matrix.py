"""Every conformance test fails against at least one simulator fault and passes without faults.

Runs the real suites (separate pytest processes, simulator in its own process) once per fault,
each fault against the suite modules it is made for (sim/engine/faults.py FAULT_GROUPS); the full
product of faults and suites is `encoder-conformance fault-matrix`. The matrix is printed in the
test output (run with -s, or see the captured stdout on failure).
"""

from __future__ import annotations

import pytest

from encoder_conformance.plugin.acceptance import GOODS_IN_ONLY
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.runs.fault_matrix import (
    CONTENT_ROOT,
    RunResult,
    format_matrix,
    read_run,
    run_matrix,
    run_until_caught,
)
from encoder_conformance.sim.fault_catalogue import FAULTS, faults_for
from tests.suite_session import PARALLEL_RUNS

#: its sessions run ahead (tests/runs_ahead.py); while it runs, no background session starts: the complement
#: matrices, made one after another from the main matrix's results, are the critical path then
FOREGROUND_SLOTS = PARALLEL_RUNS
MAIN_PROFILE = "wachendorff-wdga-mt"
#: profiles with what the WDGA lacks, tried in order: a write-only object; a store-by-reboot command;
#: every LSS service (identify, fastscan); the quirks other families document (guarding/heartbeat
#: exclusivity, immediate reload and LSS self-store on the FAULHABER, a second store object and
#: type 255 without timer on the WayCon, send-repeat counters and PDO2 disabled at init on the SIKO; the SYNC
#: start value and 1019h of the full-PDO self-test variant)
COMPLEMENT_PROFILES = [
    "tests/data/profiles/minimal-encoder.yaml",
    "tests/data/profiles/cia406-full-pdo.yaml",  # inhibit time (18xxh sub 3): test_pdo_timing's inhibit tests
    "tests/data/profiles/posital-fast-reboot.yaml",
    "cia406-c3-st",
    "faulhaber-mc5005",
    "waycon-sx",
    "siko-wx58m-1212-mt",
    "tests/data/profiles/cia406-full-pdo.yaml",  # inhibit, SYNC start value, 1019h, dummy mapping
    "tests/data/profiles/cia406-block-sdo.yaml",  # SDO block transfer: test_sdo_block
]


def _effects(profile: str) -> frozenset[str]:
    """Quirk effects of a profile id or of a profile file relative to the repository."""
    return load_profile(str(CONTENT_ROOT / profile) if "/" in profile else profile).profile.effects


def _functions(result, outcome: str) -> set[str]:
    return {name.split("::")[1].split("[")[0] for name, o in result.outcomes.items() if o == outcome}


def sessions_ahead(runs) -> dict:
    """The main matrix's sessions (tests/runs_ahead.py): the fault-free run and each fault's run; then the
    complement matrices, which wait for the main matrix's results in the background, not in this module's turn."""
    jobs = {("full", MAIN_PROFILE): lambda: runs.full_runs(MAIN_PROFILE)}
    for fault in faults_for(_effects(MAIN_PROFILE)):
        jobs[("fault", MAIN_PROFILE, fault)] = lambda fault=fault: runs.fault_runs(MAIN_PROFILE, fault)
    jobs[("fault-matrix", "main")] = lambda: _main_matrix(runs.mktemp, runs.full_runs, runs.fault_runs)
    jobs[("fault-matrix", "complements")] = lambda: _complement_matrices(
        runs.one(("fault-matrix", "main"), jobs[("fault-matrix", "main")]), runs.mktemp)
    return jobs


def _main_matrix(mktemp, full_runs, fault_runs):
    """Every fault that can show on the main profile (faults of quirks it lacks go to the complements). The
    baseline is the session's full run of the main profile's twin (tests/suite_session.py), shared with
    test_twins and test_shuffled_order: the same command the matrix ran for it, but for --tb. Each fault's run
    is the session's too (the strictly judged ones are test_inferred_walk's --strict-inferred runs)."""
    def baseline() -> RunResult:
        run = full_runs(MAIN_PROFILE)
        return read_run(None, run.folder / "report", run.completed)

    def fault_run(fault: str) -> RunResult:
        return read_run(fault, *fault_runs(MAIN_PROFILE, fault))

    faults = faults_for(_effects(MAIN_PROFILE))
    return run_matrix(MAIN_PROFILE, faults, mktemp("matrix-main"), workers=PARALLEL_RUNS,
                      targeted=True, baseline_run=baseline, fault_run=fault_run)


def _complement_matrices(main_matrix, mktemp):
    """The tests the main profile had to skip, each run on the first complement profile where it applies.

    Faults the main matrix never caught run first and always; the others only until each
    complement test has failed once (the full product would add minutes and prove nothing new).
    """
    baseline, results = main_matrix
    uncovered = _functions(baseline, "skipped") - GOODS_IN_ONLY  # only accept runs them: test_coverage_verdict.py
    caught = {r.fault for r in results if r.keys_with("failed") | r.keys_with("error")}
    unseen = frozenset(FAULTS) - caught
    order = sorted(unseen) + sorted(set(FAULTS) - unseen)
    matrices = []
    for profile in COMPLEMENT_PROFILES:
        if not uncovered:
            break
        folder = mktemp("matrix-extra")
        applicable = set(faults_for(_effects(profile)))
        matrix = run_until_caught(profile, [f for f in order if f in applicable], folder,
                                  " or ".join(sorted(uncovered)), workers=PARALLEL_RUNS, must_try=unseen & applicable,
                                  targeted=True)
        matrices.append(matrix)
        uncovered -= _functions(matrix[0], "passed")
        unseen -= {r.fault for r in matrix[1] if r.keys_with("failed") | r.keys_with("error")}
    return matrices, uncovered


@pytest.fixture(scope="module")
def main_matrix(runs_ahead):
    """The main matrix (made ahead where it could be): _main_matrix."""
    jobs = sessions_ahead(runs_ahead)
    return runs_ahead.results({key: jobs[key] for key in [("fault-matrix", "main")]})[("fault-matrix", "main")]


@pytest.fixture(scope="module")
def complement_matrices(main_matrix, runs_ahead):
    """The complement matrices (made ahead where they could be): _complement_matrices."""
    jobs = sessions_ahead(runs_ahead)
    key = ("fault-matrix", "complements")
    return runs_ahead.results({key: jobs[key]})[key]


def test_fault_free_simulator_passes_everything(main_matrix):
    baseline, _ = main_matrix
    failed = {n: o for n, o in baseline.outcomes.items() if o in ("failed", "error", "internal")}
    assert not failed, f"the fault-free {MAIN_PROFILE} twin fails: {sorted(failed)[:20]}"
    assert baseline.returncode == 0


def test_every_conformance_test_fails_against_a_fault(main_matrix, complement_matrices, capsys):
    uncaught = []
    for baseline, results in [main_matrix, *complement_matrices[0]]:
        with capsys.disabled():
            print("\n" + format_matrix(baseline, results))
        for test in sorted(baseline.keys_with("passed")):
            if not any(test in r.keys_with("failed") | r.keys_with("error") for r in results):
                uncaught.append(test)
    assert not uncaught, f"tests no fault makes fail (they prove nothing): {uncaught}"


def test_every_fault_is_caught(main_matrix, complement_matrices):
    caught = set()
    for _, results in [main_matrix, *complement_matrices[0]]:
        caught |= {r.fault for r in results if r.keys_with("failed") | r.keys_with("error")}
    assert set(FAULTS) <= caught, f"faults no test notices: {sorted(set(FAULTS) - caught)}"


def test_skipped_tests_are_covered_by_a_complement(complement_matrices):
    _, uncovered = complement_matrices
    assert not uncovered, f"tests no profile of the matrix exercises: {sorted(uncovered)}"


def test_a_matrix_run_until_caught_is_the_same_whatever_the_workers():
    """Runs started beside the one that completed the matrix are dropped: the matrix one worker would give."""
    from encoder_conformance.runs.fault_matrix import _as_if_one_at_a_time

    def run(fault: str, *failed: str) -> RunResult:
        return RunResult(fault, 1, {**{t: "failed" for t in failed}, "m::other": "passed"})

    tried = [run("a", "m::t1"), run("b"), run("c", "m::t2"), run("d", "m::t1", "m::t2")]
    assert [r.fault for r in _as_if_one_at_a_time(tried, {"m::t1", "m::t2"}, frozenset())] == ["a", "b", "c"]
    assert [r.fault for r in _as_if_one_at_a_time(tried, {"m::t1", "m::t2"}, frozenset({"d"}))] == list("abcd")
    assert [r.fault for r in _as_if_one_at_a_time(tried[:2], {"m::t1", "m::t2"}, frozenset())] == ["a", "b"]
