"""The fault matrix judges a fault with --strict-inferred exactly where the catalogue says it must
(``JUDGED_STRICTLY``: faults the suites can only see through a rule they infer). No suite runs here:
the pytest session is replaced by one that writes a JUnit file."""

from __future__ import annotations

from pathlib import Path

from encoder_conformance.plugin.verdicts import STRICT_OPTION
from encoder_conformance.runs import fault_matrix
from encoder_conformance.runs.suite_runner import SessionResult
from encoder_conformance.sim.fault_catalogue import FAULTS, JUDGED_STRICTLY

JUNIT = '<testsuite><testcase classname="suites.test_cam" name="test_something"/></testsuite>'


def test_strictly_judged_faults_are_catalogued_faults():
    assert set(FAULTS) >= JUDGED_STRICTLY


def test_only_strictly_judged_faults_run_with_strict_inferred(monkeypatch, tmp_path):
    commands: list[list[str]] = []

    def fake_pytest(command: list[str], *_: object, **__: object) -> SessionResult:
        commands.append(command)
        folder = Path(command[command.index("--ec-report-dir") + 1])
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "junit.xml").write_text(JUNIT, encoding="utf-8")
        return SessionResult(0, "")

    monkeypatch.setattr(fault_matrix, "run_pytest", fake_pytest)
    strict = sorted(JUDGED_STRICTLY)[0]
    for fault in (None, strict, "cam_polarity_ignored"):
        result = fault_matrix.run_suite("wachendorff-wdga-mt", fault, tmp_path, targeted=True)
        assert result.outcomes["test_cam::test_something"] == "passed"
    assert [STRICT_OPTION in command for command in commands] == [False, True, False]
