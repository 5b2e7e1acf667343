"""A test does not inherit a position frozen by the put-back of the test before.

SIKO devices execute some writes after their SDO reply and show the old position meanwhile (quirk
``position_frozen_during_execution``, M §5.2). The execution time belongs to the device, not to one
test's helper: here the put-back of a code-sequence test is followed at once by a preset test, the order
that failed (the preset read back as the frozen old position).
"""

from __future__ import annotations

from encoder_conformance.paths import CONTENT_ROOT, SUITES_DIR
from encoder_conformance.runs.suite_runner import run_pytest

PROFILE = "siko-wx58m-1212-mt"
MODULE = SUITES_DIR / "test_encoder_position.py"
ORDER = ("test_preset_sets_position_and_offset[zero-ccw]", "test_preset_is_kept_while_the_shaft_turns")


def test_preset_right_after_a_put_back_of_the_code_sequence(tmp_path):
    command = [*(f"{MODULE}::{name}" for name in ORDER), "-q", "-p", "no:cacheprovider", "--tb=line",
               "--ec-profile", PROFILE, "--ec-report-dir", str(tmp_path), "--ec-history", "off"]
    completed = run_pytest(command, CONTENT_ROOT, tmp_path / "pytest-output.txt", timeout=300)
    assert completed.returncode == 0, completed.output[-3000:]
    assert "2 passed" in completed.output, completed.output[-3000:]
