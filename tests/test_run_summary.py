"""RunSummary: areas from suite modules, the verdict per area and overall, the JSON round trip."""

from __future__ import annotations

from encoder_conformance.paths import SUITES_DIR
from encoder_conformance.run_summary import AREAS, MODULE_AREAS, RunSummary, TestResult, area_of


def _summary(*outcomes: tuple[str, str]) -> RunSummary:
    results = [TestResult(f"suites/{module}.py::test_{n}", area_of(f"suites/{module}.py::x"), outcome)  # type: ignore[arg-type]
               for n, (module, outcome) in enumerate(outcomes)]
    return RunSummary(kind="run", started="2026-11-26T07:00:00+00:00", profile_id="p", profile_sha256="0" * 64,
                      identity={"serial number (1018h.4)": "12345656 (0x00BC6138)", "revision (1018h.3)": "0x0001"},
                      results=results)


def test_every_suite_module_has_an_area():
    modules = {path.stem for path in SUITES_DIR.glob("test_*.py")}
    assert modules - set(MODULE_AREAS) == set(), "add the new suite module to run_summary.MODULE_AREAS"
    assert set(MODULE_AREAS.values()) <= set(AREAS)


def test_area_verdicts_and_overall():
    summary = _summary(("test_identity", "passed"), ("test_nmt", "passed"), ("test_nmt", "skipped"),
                       ("test_pdo", "warning"))
    verdicts = {a.area: a.verdict for a in summary.areas()}
    assert verdicts == {"identity": "PASS", "NMT": "PASS", "PDO": "PASS WITH WARNINGS"}
    assert summary.overall == "PASS WITH WARNINGS"
    failing = _summary(("test_identity", "passed"), ("test_emcy", "failed"), ("test_pdo", "warning"))
    assert failing.overall == "FAIL"
    assert failing.failing_areas() == ["EMCY"]
    # an internal error of the tool ("error") is no verdict about the device: in no area, no PASS either
    broken = _summary(("test_identity", "passed"), ("test_emcy", "error"), ("test_pdo", "warning"))
    assert broken.overall == "INTERNAL ERROR"
    assert broken.failing_areas() == []
    assert "EMCY" not in {a.area for a in broken.areas()}
    broken.results.append(broken.results[0].__class__("suites/test_nmt.py::t", "NMT", "failed"))
    assert broken.overall == "FAIL"


def test_not_restored_fails_and_could_not_test_wins():
    summary = _summary(("test_identity", "passed"))
    assert summary.overall == "PASS"
    summary.device_restored = False
    assert summary.overall == "FAIL"
    summary.could_not_test = "start-up check failed: no answer"
    assert summary.overall == "COULD NOT TEST"
    assert _summary(("test_nmt", "skipped")).overall == "NOT RUN"


def test_json_round_trip(tmp_path):
    summary = _summary(("test_identity", "passed"), ("test_cam", "failed"))
    summary.write(tmp_path)
    again = RunSummary.read(tmp_path)
    assert again == summary
    assert again.serial == "12345656"
    assert again.revision == "0x0001"
    assert again.overall == "FAIL"
