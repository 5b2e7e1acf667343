"""Tests own their preconditions: the suites in a shuffled order give the outcomes of the usual order.

A test that inherits a state (an error left latched, a SYNC time-out still armed, a node-ID not given back)
passes or fails by its neighbours. Here the whole suite runs against the twin in the usual order and
shuffled (``--shuffle SEED``: modules and the tests inside each), and the suite modules two conformant
variants concern run both ways against them; every test must end the same. A timing check that ends
inconclusive (the tester's host was late) counts as passed: it says nothing about the order.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from encoder_conformance.paths import CONTENT_ROOT, SUITES_DIR
from encoder_conformance.runs.fault_matrix import matrix_env
from encoder_conformance.runs.suite_runner import run_pytest
from encoder_conformance.sim.fault_catalogue import TARGET_MODULES

PROFILE = "wachendorff-wdga-mt"
#: CI runs one order every time (replayable); set ENCODER_CONFORMANCE_SHUFFLE_SEED to try others
SEED = os.environ.get("ENCODER_CONFORMANCE_SHUFFLE_SEED", "26")
#: two variants whose modules change the device's state most (LSS node-ID, SDO transfers left open)
VARIANTS = ("lss_node_id_at_reset_comm", "interrupt_aborts_open_transfer")


def _outcomes(junit: Path) -> dict[str, str]:
    """test id -> passed / failed / error / skipped: REASON (an inconclusive timing skip counts as passed)."""
    found = {}
    for case in ET.parse(junit).getroot().iter("testcase"):
        name = f"{case.get('classname', '')}::{case.get('name')}"
        skipped = case.find("skipped")
        if any(p.get("value") == "internal error" for p in case.iter("property") if p.get("name") == "verdict"):
            found[name] = "internal error"
        elif case.find("failure") is not None:
            found[name] = "failed"
        elif case.find("error") is not None:
            found[name] = "error"
        elif skipped is not None and "inconclusive" not in (skipped.get("message") or ""):
            found[name] = f"skipped: {(skipped.get('message') or '')[:80]}"
        else:
            found[name] = "passed"
    return found


def _run(folder: Path, variant: str | None, shuffled: bool) -> dict[str, str]:
    paths = [str(SUITES_DIR / f"{m}.py") for m in TARGET_MODULES[variant]] if variant else [str(SUITES_DIR)]
    command = [*paths, "-q", "-p", "no:cacheprovider", "--tb=line", "--ec-profile", PROFILE,
               "--ec-report-dir", str(folder), "--ec-history", "off"]
    command += ["--ec-sim-fault", variant] if variant else []
    command += ["--ec-shuffle", SEED] if shuffled else []
    # the environment of the shared usual-order run (tests/suite_session.py): the same hypothesis examples
    completed = run_pytest(command, CONTENT_ROOT, folder / "pytest-output.txt", timeout=600, env=matrix_env())
    return _read(folder, completed.output)


def _read(folder: Path, output: str) -> dict[str, str]:
    junit = folder / "junit.xml"
    assert junit.exists(), output[-4000:]
    return _outcomes(junit)


#: its sessions run ahead (tests/runs_ahead.py): the foreground keeps no slot of the background's
FOREGROUND_SLOTS = 0


def sessions_ahead(runs) -> dict:
    """(what, shuffled) -> its outcomes, for the twin and each variant. The twin's usual order is the session's
    full run of the WDGA twin (tests/suite_session.py, shared with test_twins and the fault matrix's baseline)."""
    def one(variant: str | None, shuffled: bool) -> dict[str, str]:
        if variant is None and not shuffled:
            run = runs.full_runs(PROFILE)
            return _read(run.folder / "report", run.completed.output)
        return _run(runs.mktemp(f"{variant or 'twin'}-{'shuffled' if shuffled else 'usual'}"), variant, shuffled)

    return {("shuffled-order", variant, shuffled): lambda v=variant, s=shuffled: one(v, s)
            for variant in (None, *VARIANTS) for shuffled in (False, True)}


@pytest.fixture(scope="module")
def pairs(runs_ahead):
    """(what, usual order, shuffled) for the twin and each variant (a few suite sessions at a time, most ahead)."""
    results = runs_ahead.results(sessions_ahead(runs_ahead))
    return [(variant or "twin", results[("shuffled-order", variant, False)], results[("shuffled-order", variant, True)])
            for variant in (None, *VARIANTS)]


def test_the_variants_exist():
    assert all(variant in TARGET_MODULES for variant in VARIANTS)


def test_shuffled_order_gives_the_same_outcomes(pairs):
    differences = []
    for what, usual, shuffled in pairs:
        assert usual, f"{what}: no test ran"
        assert set(usual) == set(shuffled), f"{what}: the shuffled run collected other tests"
        differences += [f"{what}: {test}: usual {usual[test]}, shuffled {shuffled[test]} (--shuffle {SEED})"
                        for test in sorted(usual) if usual[test] != shuffled[test]]
    assert differences == []


def test_usual_order_passes(pairs):
    """The comparison means something only where both runs are green (the twin and its variants conform)."""
    bad = [f"{what}: {test} {outcome}" for what, usual, _ in pairs for test, outcome in usual.items()
           if outcome in ("failed", "error", "internal error")]
    assert bad == []
