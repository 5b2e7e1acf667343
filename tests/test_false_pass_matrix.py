"""The false-PASS matrix (encoder_conformance/runs/false_pass_matrix.py): every way a check can end without judging
the device that a device can cause is taken by a twin fault, and that run ends FAIL or INCOMPLETE, never PASS; a run
with one guard removed is seen to pass, so the matrix can fail."""

from __future__ import annotations

from pathlib import Path

import pytest

from encoder_conformance.coverage import Hold
from encoder_conformance.runs.false_pass_matrix import PATHS, missing_paths, run_matrix, run_path
from encoder_conformance.sim.fault_catalogue import SIMULATOR_DEVIATIONS

TESTS = Path(__file__).resolve().parent


def test_every_hold_a_device_can_cause_has_a_fault():
    """A new reason to skip that a device can cause needs its twin fault in PATHS before it lands."""
    assert missing_paths() == []
    known = set(SIMULATOR_DEVIATIONS)
    assert [p.fault for p in PATHS if p.fault not in known] == []


def test_a_hold_without_a_path_is_named():
    without = tuple(p for p in PATHS if p.hold is not Hold.PERSISTENT_ERROR)
    assert missing_paths(without) == [Hold.PERSISTENT_ERROR]


@pytest.fixture(scope="module")
def matrix(tmp_path_factory) -> list:
    return run_matrix(tmp_path_factory.mktemp("false-pass"))


def test_no_path_ends_in_pass(matrix):
    """Each fault takes its path (its hold is in the run's coverage) and the run ends FAIL or INCOMPLETE."""
    lines = [result.line() for result in matrix]
    assert [r for r in matrix if not r.ok] == [], "\n".join(lines)
    assert {r.path.hold for r in matrix} == {p.hold for p in PATHS}


def test_the_matrix_sees_a_removed_guard(tmp_path, monkeypatch):
    """With the guard removed (not-testable booked as out of scope), the persistent-error path ends PASS and the
    matrix says so: the matrix can fail."""
    monkeypatch.syspath_prepend(str(TESTS))
    path = next(p for p in PATHS if p.hold is Hold.PERSISTENT_ERROR)
    result = run_path(path, tmp_path, extra=("-p", "guard_removed_plugin"))
    assert result.overall in ("PASS", "NOT RUN")
    assert not result.ok
    assert "false PASS" in result.line()
