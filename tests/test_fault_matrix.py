"""Every conformance test fails against at least one simulator fault and passes without faults.

Runs the real suites (separate pytest processes, simulator in its own process) once per fault.
The matrix is printed in the test output (run with -s, or see the captured stdout on failure).
"""

from __future__ import annotations

import pytest

from encoder_conformance.fault_matrix import format_matrix, run_matrix
from encoder_conformance.sim.faults import FAULTS

MAIN_PROFILE = "wachendorff-wdga-mt"
#: a small profile with the entry kinds the WDGA lacks (a write-only object)
COMPLEMENT_PROFILE = "tests/data/profiles/minimal-encoder.yaml"


@pytest.fixture(scope="module")
def main_matrix(tmp_path_factory):
    return run_matrix(MAIN_PROFILE, sorted(FAULTS), tmp_path_factory.mktemp("matrix-main"), workers=2)


@pytest.fixture(scope="module")
def complement_matrix(main_matrix, tmp_path_factory):
    """The tests the main profile had to skip, run on a profile where they apply."""
    baseline, _ = main_matrix
    skipped = sorted({name.split("::")[1].split("[")[0] for name, o in baseline.outcomes.items() if o == "skipped"})
    if not skipped:
        return None
    return run_matrix(
        COMPLEMENT_PROFILE, sorted(FAULTS), tmp_path_factory.mktemp("matrix-extra"), " or ".join(skipped), workers=2
    )


def test_fault_free_simulator_passes_everything(main_matrix):
    baseline, _ = main_matrix
    failed = {n: o for n, o in baseline.outcomes.items() if o in ("failed", "error")}
    assert not failed, f"the fault-free {MAIN_PROFILE} twin fails: {sorted(failed)[:20]}"
    assert baseline.returncode == 0


def test_every_conformance_test_fails_against_a_fault(main_matrix, complement_matrix, capsys):
    uncaught = []
    for baseline, results in filter(None, (main_matrix, complement_matrix)):
        with capsys.disabled():
            print("\n" + format_matrix(baseline, results))
        for test in sorted(baseline.keys_with("passed")):
            if not any(test in r.keys_with("failed") | r.keys_with("error") for r in results):
                uncaught.append(test)
    assert not uncaught, f"tests no fault makes fail (they prove nothing): {uncaught}"


def test_every_fault_is_caught(main_matrix, complement_matrix):
    caught = set()
    for _, results in filter(None, (main_matrix, complement_matrix)):
        caught |= {r.fault for r in results if r.keys_with("failed") | r.keys_with("error")}
    assert set(FAULTS) <= caught, f"faults no test notices: {sorted(set(FAULTS) - caught)}"


def test_skipped_tests_are_covered_by_the_complement(main_matrix, complement_matrix):
    baseline, _ = main_matrix
    skipped = {n.split("::")[1].split("[")[0] for n, o in baseline.outcomes.items() if o == "skipped"}
    if not skipped:
        return
    extra_baseline, _ = complement_matrix
    ran = {n.split("::")[1].split("[")[0] for n, o in extra_baseline.outcomes.items() if o == "passed"}
    assert skipped <= ran, f"tests neither profile exercises: {sorted(skipped - ran)}"
