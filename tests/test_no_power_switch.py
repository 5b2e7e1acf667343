"""A bench without a power switch (a plain USB-CAN adapter and a device on a lab supply): tests that need one
skip and say how to give one; none fails for the want of it. Seen: the WDGA's unconfigured start-up (its
manual applies an LSS node-ID only at power-on) failed with "there is no power switch" against an external
twin with --allow-destructive."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from encoder_conformance.exit_codes import RunExit
from tests.bench_twin import REPO, start_twin

#: the tests that need the power switch on the WDGA (LSS node-ID applied at power-on, stored values)
NEEDS_POWER = ("test_unconfigured_start_up", "test_store_configuration_survives_power_cycle")
#: and one that needs no switch (a run where every test skips checked nothing, and fails)
NEEDS_NOTHING = "test_inquire_identity_equals_1018h"


def test_tests_needing_power_skip_without_a_switch(tmp_path):
    twin = start_twin(tmp_path / "twin")
    try:
        command = [sys.executable, "-m", "encoder_conformance", "run", "--profile", twin.profile,
                   "--can-interface", "remote", "--can-channel", twin.channel, "--report-dir", str(tmp_path / "report"),
                   "--allow-destructive", "--history", "off", "-k", " or ".join((*NEEDS_POWER, NEEDS_NOTHING))]
        env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
        completed = subprocess.run(command, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    finally:
        twin.close()
    assert completed.returncode == RunExit.PASSED, completed.stdout[-3000:]
    results = json.loads((tmp_path / "report" / "run-summary.json").read_text(encoding="utf-8"))["results"]
    selected = [r for r in results if r["nodeid"].rsplit("::", 1)[-1] in NEEDS_POWER]
    assert len(selected) == len(NEEDS_POWER), [r["nodeid"] for r in results]
    for result in selected:
        assert result["outcome"] == "skipped", result
        assert "needs a power switch" in result["message"], result
        assert "--power-off-cmd" in result["message"], result
