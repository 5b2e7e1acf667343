"""A fault a check cannot judge ends the run INCOMPLETE, never PASS and never FAIL: each hold fault
(``sim/hold_faults.py``) against its target modules, every check it holds naming the hold it was made for."""

from __future__ import annotations

import json

import pytest

from encoder_conformance.exit_codes import RunExit
from encoder_conformance.runs.fault_matrix import run_suite
from encoder_conformance.sim.hold_faults import HOLD_FAULTS

PROFILE = "wachendorff-wdga-mt"


@pytest.mark.parametrize("fault", sorted(HOLD_FAULTS))
def test_a_hold_fault_makes_the_run_incomplete(fault, tmp_path):
    result = run_suite(PROFILE, fault, tmp_path, targeted=True)
    bad = sorted(name for name, outcome in result.outcomes.items() if outcome in ("failed", "error", "internal"))
    assert bad == [], f"{fault}: a check that cannot judge failed the device"
    assert result.returncode == RunExit.INCOMPLETE
    summary = json.loads((tmp_path / fault / "run-summary.json").read_text(encoding="utf-8"))
    holds = {r["hold"] for r in summary["results"] if r["outcome"] == "skipped" and r.get("hold")}
    assert holds == {HOLD_FAULTS[fault].hold}, f"{fault}: holds named {holds}"
