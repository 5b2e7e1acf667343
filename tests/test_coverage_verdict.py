"""Coverage is part of the verdict (encoder_conformance/coverage.py, plugin/skips.py, run_summary.py): a check in
scope that did not judge makes its area INCOMPLETE (exit 6), an inconclusive one at most PASS WITH WARNINGS, a check
outside the scope is listed and not counted; FAIL outranks INCOMPLETE. Against the twin: the device that reports an
error at every start and never stays operational is INCOMPLETE in a run and FAILs goods-in; a conformant twin
passes both."""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from encoder_conformance.coverage import Hold, Kind, kind_of
from encoder_conformance.errors import HeldByPersistentError, NotJudged
from encoder_conformance.exit_codes import DESCRIPTIONS, RunExit
from encoder_conformance.plugin import junit_coverage
from encoder_conformance.plugin.skips import TypedSkip, kind_and_hold, not_applicable, not_judged
from encoder_conformance.run_summary import AreaVerdict, RunSummary, TestResult

REPO = Path(__file__).resolve().parents[1]
NMT = "suites/test_nmt.py::test_"


def _result(name: str, outcome: str, kind: Kind | None = None, hold: Hold | None = None,
            area: str = "NMT") -> TestResult:
    return TestResult(NMT + name, area, outcome, message=f"{kind.value}: why" if kind else "",  # type: ignore[arg-type]
                      skip_kind=kind.value if kind else None, hold=hold.name if hold else None)


def _summary(*results: TestResult) -> RunSummary:
    return RunSummary("run", "2026-12-07T00:00:00+00:00", "p", "0" * 64, results=list(results))


def _area(*results: TestResult) -> AreaVerdict:
    area = AreaVerdict("NMT")
    for result in results:
        area.count(result)
    return area


PASSED = _result("a", "passed")
HELD = _result("b", "skipped", Kind.NOT_TESTABLE, Hold.PERSISTENT_ERROR)
LATE = _result("c", "skipped", Kind.INCONCLUSIVE, Hold.HOST_LATE)
SCOPE = _result("d", "skipped", Kind.NOT_APPLICABLE)
FAILED = _result("e", "failed")


@pytest.mark.parametrize(("results", "verdict"), [
    ((PASSED,), "PASS"),
    ((PASSED, SCOPE), "PASS"),  # out of scope: listed, not counted
    ((SCOPE,), "NOT RUN"),
    ((PASSED, HELD), "INCOMPLETE"),
    ((HELD,), "INCOMPLETE"),
    ((PASSED, HELD, FAILED), "FAIL"),  # FAIL outranks INCOMPLETE
    ((PASSED, LATE), "PASS WITH WARNINGS"),  # inconclusive: at most PASS WITH WARNINGS
    ((PASSED, LATE, HELD), "INCOMPLETE"),
])
def test_area_verdict_counts_coverage(results, verdict):
    assert _area(*results).verdict == verdict


def test_overall_incomplete_lists_its_areas_and_reasons():
    summary = _summary(PASSED, HELD, _result("x", "passed", area="identity"), SCOPE)
    assert summary.overall == "INCOMPLETE"
    assert summary.incomplete_areas() == ["NMT"]
    coverage = summary.coverage()
    assert coverage["holds"] == {"PERSISTENT_ERROR": 1}
    assert coverage["skipped_by_kind"] == {"not testable": 1, "not applicable": 1}
    assert coverage["checked"] == 2
    again = RunSummary.from_json(summary.to_json())
    assert again.overall == "INCOMPLETE"
    assert again.results[1].kind is Kind.NOT_TESTABLE


def test_precedence_fail_and_internal_error_outrank_incomplete():
    assert _summary(PASSED, HELD, FAILED).overall == "FAIL"
    assert _summary(PASSED, HELD, _result("z", "error")).overall == "INTERNAL ERROR"


def test_a_summary_from_before_typed_skips_keeps_its_verdict():
    """Records kept no kind then: their skips count as that version counted them (out of scope)."""
    old = TestResult(NMT + "old", "NMT", "skipped", message="needs a power switch: configure one")
    assert old.kind is Kind.NOT_APPLICABLE
    assert _summary(PASSED, old).overall == "PASS"


def test_an_untyped_skip_in_a_run_is_not_testable():
    assert kind_of("whatever the reason") is Kind.NOT_TESTABLE
    assert kind_of("not applicable: no LSS") is Kind.NOT_APPLICABLE
    assert kind_and_hold(None, "a library's own skip") == (Kind.NOT_TESTABLE, Hold.UNTYPED)
    assert kind_and_hold(None, "not available: no power switch") == (Kind.NOT_EQUIPPED, None)


def test_typed_skips_and_not_judged_carry_their_hold():
    with pytest.raises(TypedSkip) as skipped:
        not_judged(Hold.VALUES_CHANGED, "6004h changed between the reads")
    assert skipped.value.msg == "not testable: 6004h changed between the reads"
    assert kind_and_hold(skipped.value, "") == (Kind.NOT_TESTABLE, Hold.VALUES_CHANGED)
    with pytest.raises(TypedSkip) as scope:
        not_applicable("no LSS")
    assert (scope.value.kind, scope.value.hold) == (Kind.NOT_APPLICABLE, None)
    held = HeldByPersistentError("not testable: NMT start: 1001h = 01h")
    assert isinstance(held, NotJudged)
    assert str(held) == "not testable: NMT start: 1001h = 01h"
    assert kind_and_hold(held, str(held)) == (Kind.NOT_TESTABLE, Hold.PERSISTENT_ERROR)


def test_every_hold_says_what_it_means_and_incomplete_has_an_exit_code_of_its_own():
    assert all(hold.meaning and hold.kind.in_scope for hold in Hold)
    assert not any(kind.in_scope for kind in (Kind.NOT_APPLICABLE, Kind.NOT_EQUIPPED, Kind.NOT_SELECTED))
    assert RunExit.INCOMPLETE not in (0, 1, 2, 3, 4, 5, 69, 70, 130, 143)
    assert list(RunExit).count(RunExit.INCOMPLETE) == 1
    assert "incomplete" in DESCRIPTIONS[RunExit.INCOMPLETE]


JUNIT = """<?xml version="1.0" encoding="utf-8"?><testsuites><testsuite name="pytest" errors="0" failures="0"
skipped="1" tests="2"><testcase classname="suites.test_nmt" name="test_a"/><testcase classname="suites.test_nmt"
name="test_b"><skipped message="not testable: why"/></testcase></testsuite></testsuites>"""


@pytest.mark.parametrize(("results", "fails"), [((PASSED, HELD), True), ((PASSED, SCOPE), False)])
def test_junit_gets_a_coverage_case_a_ci_does_not_count_as_green(tmp_path, results, fails):
    path = tmp_path / "junit.xml"
    path.write_text(JUNIT, encoding="utf-8")
    summary = _summary(*results)
    assert junit_coverage.add(path, summary)
    suite = ET.parse(path).getroot().find("testsuite")
    assert suite is not None
    case = [c for c in suite.iter("testcase") if c.get("name") == junit_coverage.CASE_NAME]
    assert len(case) == 1
    assert (case[0].find("failure") is not None) == fails
    assert suite.get("failures") == ("1" if fails else "0")
    assert suite.get("tests") == "3"
    assert {p.get("name"): p.get("value") for p in suite.iter("property")} == {
        junit_coverage.PROPERTY: summary.overall}


# -- against the twin ------------------------------------------------------------------------------------------

def _command(tmp_path: Path, command: str, *args: str) -> tuple[subprocess.CompletedProcess[str], RunSummary]:
    result = subprocess.run([sys.executable, "-m", "encoder_conformance", command, "--profile", "wachendorff-wdga-mt",
                             "--report-dir", str(tmp_path / "report"), "--history", "off", *args],
                            cwd=REPO, capture_output=True, text=True, timeout=300)
    found = sorted(tmp_path.rglob("run-summary.json"))
    assert found, f"no run-summary.json\n{result.stdout}\n{result.stderr}"
    return result, RunSummary.read(found[-1])


def test_a_device_with_an_error_at_every_start_is_incomplete_in_a_run(tmp_path):
    """The twin's variant device_error_at_start: nothing fails, the checks that need operational are not testable:
    INCOMPLETE, exit 6, with the coverage per area and the reason; JUnit's coverage case fails."""
    result, summary = _command(tmp_path, "run", "--sim-fault", "device_error_at_start", "-k",
                               "test_nmt.py or test_identity.py", "--junitxml", str(tmp_path / "junit.xml"))
    assert result.returncode == RunExit.INCOMPLETE, result.stdout[-3000:] + result.stderr[-3000:]
    assert summary.overall == "INCOMPLETE"
    assert "NMT" in summary.incomplete_areas()
    assert {a.area: a.verdict for a in summary.areas()}["identity"] == "PASS"
    assert summary.coverage()["holds"].get("PERSISTENT_ERROR", 0) > 0
    assert "INCOMPLETE: " in result.stdout
    assert "not testable: " in result.stdout
    assert all("1001h = 01h" in r.message for r in summary.with_kind(Kind.NOT_TESTABLE))
    cases = ET.parse(tmp_path / "junit.xml").getroot().iter("testcase")
    coverage = [case for case in cases if case.get("name") == junit_coverage.CASE_NAME]
    assert len(coverage) == 1
    assert coverage[0].find("failure") is not None


def test_goods_in_fails_a_device_with_an_error_at_every_start(tmp_path):
    """accept: FAIL (exit 1) in the working-order area, naming EMCY 5000h and its meaning."""
    result, summary = _command(tmp_path, "accept", "--sim-fault", "device_error_at_start")
    assert result.returncode == RunExit.NON_CONFORMANT, result.stdout + result.stderr
    assert summary.overall == "FAIL"
    assert "working order" in summary.failing_areas()
    assert "EMCY 5000h (device hardware)" in result.stdout


def test_a_conformant_twin_passes_goods_in_and_a_run_without_power_switch_declares_its_scope(tmp_path):
    result, summary = _command(tmp_path, "accept")
    assert result.returncode == RunExit.PASSED, result.stdout + result.stderr
    assert {a.area: a.verdict for a in summary.areas()}["working order"] == "PASS"
    assert summary.scope["power switch"].startswith("none")
    assert summary.scope["destructive checks"].startswith("left out")
