"""Allure says the same as the run (issue 39): ``--allure`` results rendered by allure's own command-line tool show
the areas as suites and behaviours (epic, feature), the clause as story, the basis as tag, each test's outcome as
the run summary has it, the run's verdict, the device and the settings as environment, and the outcomes that are no
plain pass by category. The rendering test skips where the tool (npm package allure-commandline, on Java) is not
installed; CI installs it (.ci/run). The files and labels are checked without it too.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import time
import uuid
from pathlib import Path
from types import SimpleNamespace

import pytest

from encoder_conformance.plugin import allure_labels, allure_run
from encoder_conformance.run_summary import RunSummary, TestResult
from tests.suite_session import REPO, run_suite

#: a short WayCon run with every plain outcome: a device failure (the fault), passes, skips that do not apply
SELECTION = "test_identity or test_heartbeat_frame_format or test_heartbeat_zero_disables"
FAULT = "wrong_identity_size"
FAILED = "test_identity_record_size"

#: the outcomes a short run does not show, as the plugin would write them (name, outcome, message)
SYNTHETIC = [
    ("synthetic_warning", "warning", "1800h answered 08000020h [inferred: capabilities.x]"),
    ("synthetic_internal_error", "error", "AttributeError: 'NoneType' object has no attribute 'code'"),
    ("synthetic_not_testable", "skipped", "not testable: the TPDO stream: the device keeps an error"),
    ("synthetic_inconclusive", "skipped", "inconclusive: the SYNCs carry the host's delays"),
    ("synthetic_could_not_test", "skipped", "could not test: the read of every entry overran"),
    ("synthetic_bus_lost", "skipped", "not run to the end: the bus is gone"),
    ("synthetic_not_available", "skipped", "not available: no shaft drive (--shaft-drive)"),
    ("synthetic_destructive", "skipped", "not selected: destructive (changes what the device remembers): run "
                                         "with --allow-destructive"),
]
EXPECTED_CATEGORY = {
    "synthetic_warning": "warning: a rule we inferred was broken",
    "synthetic_internal_error": "internal error of the tool",
    "synthetic_not_testable": "not testable",
    "synthetic_inconclusive": "inconclusive",
    "synthetic_could_not_test": "could not test",
    "synthetic_bus_lost": "could not test",
    "synthetic_not_available": "bench equipment not available",
    "synthetic_destructive": "not selected (e.g. destructive: not run without --allow-destructive)",
}


def allure_tool() -> str | None:
    """The allure command-line tool: CI's local install (.ci/run), else one on PATH; None without it or Java."""
    local = REPO / ".ci" / "node" / "node_modules" / ".bin" / "allure"
    tool = str(local) if local.exists() else shutil.which("allure")
    return tool if tool and shutil.which("java") else None


def _summary(*results: TestResult) -> RunSummary:
    return RunSummary(kind="run", started="2026-12-07T05:00:00+00:00", profile_id="waycon-sx", profile_sha256="ab12",
                      identity={"vendor-id (1018h.1)": "0x0000FFFE", "name (1008h)": "Gerät §5"},
                      settings={"interface": "simulator (from default)", "node-id": "7 (from profile)"},
                      results=list(results), device_restored=True)


def _java_properties(text: str) -> dict[str, str]:
    """Enough of java.util.Properties' reading for the lines allure_run writes (one pair a line)."""
    values = {}
    for line in text.splitlines():
        key, value = re.split(r"(?<!\\)=", line, maxsplit=1)
        values[_unescape(key)] = _unescape(value)
    return values


def _unescape(text: str) -> str:
    text = re.sub(r"\\u([0-9a-f]{4})", lambda m: chr(int(m.group(1), 16)), text)
    text = text.encode("utf-16", "surrogatepass").decode("utf-16")  # join the pairs of a character beyond the BMP
    return re.sub(r"\\(.)", lambda m: {"n": "\n", "r": "\r", "t": "\t"}.get(m.group(1), m.group(1)), text)


def test_environment_properties_hold_the_verdict_device_and_settings(tmp_path):
    """The run's verdict first, each area's, the device's identity and each setting with its source; ASCII only,
    escaped as java.util.Properties reads it (spaces, colons in keys; § and beyond as \\u escapes)."""
    summary = _summary(TestResult("suites/test_nmt.py::test_a", "NMT", "failed", "cia", "CiA 301 §7.2", "x"),
                       TestResult("suites/test_identity.py::test_b", "identity", "passed", "cia"))
    allure_run.write(tmp_path, summary)
    text = (tmp_path / "environment.properties").read_text(encoding="ascii")
    values = _java_properties(text)
    assert next(iter(values)) == "verdict"
    assert values["verdict"] == "FAIL"
    assert values["area NMT"] == "FAIL"
    assert values["area identity"] == "PASS"
    assert values["identity name (1008h)"] == "Gerät §5"
    assert values["interface"] == "simulator (from default)"
    assert values["device given back as found"] == "yes"
    assert "identity\\ vendor-id\\ (1018h.1)=0x0000FFFE" in text.splitlines()
    assert _java_properties(allure_run.properties_text({"a:b": " x=😀"})) == {"a:b": " x=😀"}
    assert json.loads((tmp_path / "executor.json").read_text())["reportName"] == "waycon-sx: FAIL"


def test_each_kind_of_outcome_falls_in_one_category():
    """categories.json: every synthetic outcome matches exactly one category (Python's re reads these patterns as
    Java's does), the plain pass and a not applicable skip each theirs or none."""
    def categories(status: str, message: str | None) -> list[str]:
        return [c["name"] for c in allure_run.CATEGORIES if status in c["matchedStatuses"]
                and ("messageRegex" not in c or (message is not None and re.fullmatch(c["messageRegex"], message)))]

    for name, outcome, message in SYNTHETIC:
        result = TestResult(f"suites/test_x.py::{name}", "other", outcome, message=message)
        assert categories(allure_labels.STATUS[outcome], allure_labels.message_of(result)) == [
            EXPECTED_CATEGORY[name]], name
    assert categories("passed", None) == []
    assert categories("skipped", "not applicable: the profile gives no revision range") == ["not applicable"]
    assert categories("skipped", "Skipped: Not applicable: typed anew") == ["not applicable"]
    assert categories("failed", "AssertionError: 1018h.00: expected 2") == ["device failure"]


def test_the_open_allure_result_gets_the_runs_labels_and_status():
    """amend() replaces allure-pytest's suite 'suites' and status by the run's: area, module, clause, basis; a
    warning passes with its problems as message; again after a later phase without doubling a label."""
    from allure_commons.model2 import Label, StatusDetails
    from allure_commons.model2 import TestResult as AllureResult

    held = AllureResult(name="test_a", status="failed", labels=[Label("parentSuite", "suites"), Label("suite", "x")],
                        statusDetails=StatusDetails(message="AssertionError: raw", trace="trace"))
    logger = SimpleNamespace(get_test=lambda uuid: held)
    config = SimpleNamespace(pluginmanager=SimpleNamespace(get_plugin=lambda name: SimpleNamespace(
        allure_logger=logger)))
    item = SimpleNamespace(config=config)
    result = TestResult("suites/test_nmt_state_machine.py::test_a", "NMT", "warning", "inferred", "our reading",
                        "1800h answered 08000020h")
    allure_labels.amend(item, result)
    allure_labels.amend(item, result)
    labels = sorted((label.name, label.value) for label in held.labels)
    assert labels == [("epic", "NMT"), ("feature", "nmt state machine"), ("parentSuite", "NMT"),
                      ("story", "our reading"), ("suite", "x"), ("tag", "basis: inferred")]
    assert held.status == "passed"
    assert held.statusDetails.message == "warning: 1800h answered 08000020h"
    assert held.statusDetails.trace is None


def test_a_run_without_allure_imports_none_of_it():
    """The plugin's modules (those behind the hub, which imports them at their first use) and the evidence
    fixtures import allure only where results are written (allure_labels.amend, fixtures/evidence.py's
    attachments): the import costs every run ~60 ms (option_table.unused_plugins)."""
    code = ("import sys, pkgutil, importlib, encoder_conformance.plugin as plugin\n"
            "import encoder_conformance.plugin.fixtures.evidence\n"
            "for module in pkgutil.iter_modules(plugin.__path__):\n"
            "    importlib.import_module(f'encoder_conformance.plugin.{module.name}')\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('allure', 'allure_commons', 'allure_pytest')))")
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def _write_synthetic(results: Path) -> None:
    """Result files for the outcomes a short run does not show, labelled as the plugin labels them."""
    for name, outcome, message in SYNTHETIC:
        result = TestResult(f"suites/test_synthetic.py::{name}", "other", outcome, "inferred", "ours",
                            message)
        data = {"uuid": str(uuid.uuid4()), "name": name, "fullName": f"suites.test_synthetic#{name}",
                "historyId": name, "status": allure_labels.STATUS[outcome],
                "statusDetails": {"message": allure_labels.message_of(result)}, "start": 1, "stop": 2,
                "labels": [{"name": k, "value": v} for k, v in allure_labels.labels_of(result)]}
        (results / f"{data['uuid']}-result.json").write_text(json.dumps(data), encoding="utf-8")


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """A short --allure run against the WayCon twin with one fault, its results rendered by `allure generate`."""
    tool = allure_tool()
    if tool is None:
        pytest.skip("allure command-line tool not installed (npm install --prefix .ci/node allure-commandline; "
                    "it runs on Java)")
    folder = tmp_path_factory.mktemp("allure")
    start = time.monotonic()
    completed, _ = run_suite(folder, "--ec-profile", "waycon-sx", "-k", SELECTION, "--ec-sim-fault", FAULT,
                             "--ec-allure", "--ec-history", "off")
    ran = time.monotonic()
    results = folder / "report" / "allure-results"
    assert results.is_dir(), completed.output[-3000:]
    _write_synthetic(results)
    out = folder / "allure-report"
    done = subprocess.run([tool, "generate", str(results), "-o", str(out), "--clean"], capture_output=True,
                          text=True, timeout=180)
    assert done.returncode == 0, f"allure generate failed:\n{done.stdout}{done.stderr}"
    print(f"\nallure: suite run {ran - start:.1f} s, allure generate {time.monotonic() - ran:.1f} s")
    return out, RunSummary.read(folder / "report"), completed


def _read(out: Path, name: str):
    return json.loads((out / name).read_text(encoding="utf-8"))


def _leaves(node: dict, path: tuple[str, ...] = ()):
    """(path of group names, leaf) for every test in one of allure's trees."""
    for child in node.get("children", []):
        if "children" in child:
            yield from _leaves(child, (*path, child["name"]))
        else:
            yield path, child


def test_allure_shows_the_areas_outcomes_and_clauses(rendered):
    """Suites by area (not one 'suites'), behaviours as area > module > clause, the basis as tag, and each test's
    status as the run summary's outcome."""
    out, summary, completed = rendered
    outcomes = {result.outcome for result in summary.results}
    assert {"failed", "passed", "skipped"} <= outcomes, completed.output[-2000:]
    suites = {path[0] for path, _ in _leaves(_read(out, "data/suites.json"))}
    assert {"identity", "error control"} <= suites
    assert "suites" not in suites
    behaviours = {leaf["name"]: (path, leaf) for path, leaf in _leaves(_read(out, "data/behaviors.json"))}
    path, leaf = behaviours[FAILED]
    assert path == ("identity", "identity", "CiA 301 §7.5.2.23 (1018h sub 0 highest sub-index)")
    assert "basis: cia" in leaf["tags"]
    status = {name: leaf["status"] for name, (_, leaf) in behaviours.items()}
    for result in summary.results:
        name = result.nodeid.split("::")[-1]
        assert status[name] == allure_labels.STATUS[result.outcome], name


def test_allure_environment_holds_the_verdict_device_and_settings(rendered):
    out, summary, _ = rendered
    environment = {entry["name"]: entry["values"] for entry in _read(out, "widgets/environment.json")}
    assert environment["verdict"] == [summary.overall] == ["FAIL"]
    assert {name: values for name, values in environment.items() if name.startswith("area ")} == {
        f"area {area.area}": [area.verdict] for area in summary.areas()}
    assert environment["area identity"] == ["FAIL"]
    assert environment["identity vendor-id (1018h.1)"] == [summary.identity["vendor-id (1018h.1)"]]
    assert environment["node-id"] == [summary.settings["node-id"]]
    assert environment["profile"] == ["waycon-sx"]
    assert _read(out, "widgets/summary.json")["reportName"] == "waycon-sx: FAIL"


def test_allure_categories_tell_the_outcomes_apart(rendered):
    out, summary, _ = rendered
    category = {leaf["name"]: path[0] for path, leaf in _leaves(_read(out, "data/categories.json"))}
    assert category[FAILED] == "device failure"
    not_applicable = [r.nodeid.split("::")[-1] for r in summary.with_outcome("skipped")
                      if r.message.startswith("not applicable:")]
    assert not_applicable
    assert all(category[name] == "not applicable" for name in not_applicable)
    for name, expected in EXPECTED_CATEGORY.items():
        assert category[name] == expected, name
