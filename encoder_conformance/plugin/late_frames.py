"""Late frames in the verdict: a frame attributed to a closed "must not come" window (``dut/link/late_frames.py``)
fails the test that owned the window if that test has not reported yet (checked before each of its reports), or
else a run-level check that names it: a result in run-summary.json (``late frame: <test id>``), a line in the
terminal and HTML summaries, a JUnit testcase, and the exit code of a failed run. The run cannot end PASS with an
unattributed late frame. An inconclusive one (the host was late) is listed, never a failure, and is an inconclusive
check of its own (``late frame (inconclusive): <test id>``, ``Hold.HOST_LATE``): its area is at most PASS WITH
WARNINGS, as the window's check could not be trusted to have seen what it proved absent.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

from encoder_conformance.basis import Basis
from encoder_conformance.coverage import Hold, Kind
from encoder_conformance.dut.link.late_frames import LATE_RULE, LateFrame, LateLedger, Owner
from encoder_conformance.plugin import lifecycle, run_record
from encoder_conformance.run_summary import RunSummary, TestResult, area_of

#: every late frame of the run, as judged (stash of the config)
FOUND = pytest.StashKey[list[LateFrame]]()
#: those whose owner had reported: run-level checks
RUN_LEVEL = pytest.StashKey[list[LateFrame]]()
#: the prefix of a run-level check's node id
CHECK = "late frame: "
#: the prefix of an inconclusive late frame's check
UNSURE = "late frame (inconclusive): "
JUNIT_CLASS = "encoder_conformance.late_frames"
SECTION = "late frames"


def _ledger(config: pytest.Config) -> LateLedger | None:
    custody = lifecycle.custody_of(config)
    return None if custody is None else custody.dut.frames.late


def _take(config: pytest.Config, owner: str | None) -> list[LateFrame]:
    ledger = _ledger(config)
    if ledger is None:
        return []
    taken = ledger.judged(owner)
    config.stash.setdefault(FOUND, []).extend(taken)
    return taken


def begin(item: pytest.Item) -> None:
    """The windows declared from now on are this test's."""
    Owner.nodeid = item.nodeid


def end(item: pytest.Item) -> None:
    Owner.nodeid = f"between tests (after {item.nodeid})"


def judge(item: pytest.Item, report: pytest.TestReport) -> None:
    """Before the test's call and teardown reports: its late frames fail it (an inconclusive one is noted)."""
    if report.when == "setup" and report.passed:
        return
    taken = _take(item.config, item.nodeid)
    if not taken:
        return
    text = "\n".join(late.describe() for late in taken)
    report.sections.append((SECTION, text))
    report.user_properties.append(("late_frames", text))
    failing = [late for late in taken if late.verdict == "fail"]
    if failing and not report.failed:
        report.outcome = "failed"
        report.longrepr = f"{len(failing)} frame(s) after the window that proved them absent:\n{text}"
        report.user_properties.append(("verdict_source", failing[0].window.basis))


def linger(config: pytest.Config) -> None:
    """In the last test's teardown, before the session's fixtures end (the twin, the give-back and its resets):
    listen out the newest window's linger (a silence window: frames that must not come)."""
    custody = lifecycle.custody_of(config)
    if custody is not None and custody.dut.usable and (seconds := custody.dut.frames.late.linger_s()) > 0:
        custody.dut.frames.quiet_period(lambda m: False, seconds)


def settle(config: pytest.Config) -> None:
    """At the session's end: the late frames no running test took become run-level checks (a FAIL each)."""
    summary = run_record.summary_of(config)
    state = lifecycle.state_of(config)
    for late in _take(config, None):
        if late.verdict != "fail":
            continue
        nodeid = CHECK + late.window.owner
        config.stash.setdefault(RUN_LEVEL, []).append(late)
        if state is not None:
            state.failed_tests.add(nodeid)
        if summary is not None and not any(r.nodeid == nodeid for r in summary.results):
            summary.results.append(TestResult(nodeid, area_of(late.window.owner), "failed", _basis(late),
                                              f"{late.window.basis}; {LATE_RULE}", late.describe()))
    if summary is not None:
        found = config.stash.get(FOUND, [])
        summary.late_frames = [late.describe() for late in found]
        for late in found:
            if late.verdict == "inconclusive":
                _unsure(summary, late)


def _unsure(summary: RunSummary, late: LateFrame) -> None:
    """An inconclusive late frame as an inconclusive check (once per owning test)."""
    nodeid = UNSURE + late.window.owner
    if not any(r.nodeid == nodeid for r in summary.results):
        summary.results.append(TestResult(nodeid, area_of(late.window.owner), "skipped", _basis(late),
                                          f"{late.window.basis}; {LATE_RULE}",
                                          f"{Kind.INCONCLUSIVE.value}: {late.describe()}",
                                          skip_kind=Kind.INCONCLUSIVE.value, hold=Hold.HOST_LATE.name))


def _basis(late: LateFrame) -> Basis:
    """The window's clause: a CiA document's, else the manual's."""
    return "cia" if late.window.basis.startswith("CiA") else "manual"


def summary_lines(config: pytest.Config) -> list[tuple[str, bool]]:
    """(text, alarm) lines for the terminal and the HTML summary."""
    found = config.stash.get(FOUND, [])
    return [(late.describe(), late.verdict == "fail") for late in found]


def terminal_section(terminalreporter: Any, config: pytest.Config) -> None:
    """The late frames in the terminal summary, each with its owner, window, lateness and basis."""
    lines = summary_lines(config)
    if lines:
        terminalreporter.write_sep("-", "late frames: after the window that proved them absent", red=True)
        for text, alarm in lines:
            terminalreporter.write_line(text, red=alarm, yellow=not alarm)


def add_to_junit(junit: Path, config: pytest.Config) -> None:
    """One failing testcase per late frame whose owner had already reported (the run-level check)."""
    run_level = config.stash.get(RUN_LEVEL, [])
    if not run_level or not junit.is_file():
        return
    tree = ET.parse(junit)
    root = tree.getroot()
    suite = root if root.tag == "testsuite" else root.find("testsuite")
    if suite is None:
        return
    for late in run_level:
        case = ET.SubElement(suite, "testcase", classname=JUNIT_CLASS, name=CHECK + late.window.owner, time="0")
        ET.SubElement(case, "failure", message="a late frame").text = late.describe()
        suite.set("failures", str(int(suite.get("failures", "0")) + 1))
        suite.set("tests", str(int(suite.get("tests", "0")) + 1))
    tree.write(junit, encoding="utf-8", xml_declaration=True)
