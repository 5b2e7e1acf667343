"""The report read at a glance (issue 14, part 5): the first screen from a RunSummary, the bus-trace policy, the
skip reasons as text, and the size of a report folder.

The page is tested without a browser: from a hand-made RunSummary (order, folds, alarms), and once end to end
against the WDGA twin with a heartbeat fault (banner before pytest-html's table, traces only for the failure).
"""

from __future__ import annotations

import base64
import json
import re
from pathlib import Path
from types import SimpleNamespace
from xml.etree import ElementTree

import can
import pytest

from encoder_conformance.plugin import bus_trace, reporting
from encoder_conformance.plugin.evidence import EVIDENCE, Evidence
from encoder_conformance.plugin.glance import Deviation, PageContext, render, skip_reason_key
from encoder_conformance.plugin.options import TRACE_OPTION
from encoder_conformance.run_summary import RunSummary, TestResult
from tests.suite_session import run_suite

IDENTITY = {"vendor-id (1018h.1)": "0x0100021F", "product code (1018h.2)": "0x57444741",
            "revision (1018h.3)": "0x03060208", "serial number (1018h.4)": "12345656 (0x00BC6138)",
            "device type (1000h)": "0x00020196", "device name (1008h)": "WDGA-MT-CO"}


def _summary(*results: TestResult, restored: bool | None = True, stopped: str | None = None) -> RunSummary:
    return RunSummary(kind="run", started="2026-11-26T06:30:41+00:00", profile_id="wachendorff-wdga-mt",
                      profile_sha256="d4e1", duration_s=32.4, identity=dict(IDENTITY),
                      settings={"interface": "pcan (from station bench.toml)"}, station="bench-3", operator="Ana",
                      results=list(results), device_restored=restored, could_not_test=stopped)


PASSED = TestResult("suites/test_nmt.py::test_start", "NMT", "passed", "cia", "CiA 301 §7.2.8")
FAILED = TestResult("suites/test_heartbeat.py::test_period", "error control", "failed", "cia",
                    "CiA 301 §7.2.8.3.2.2", "heartbeat: period 60.01 ms, expected 50 ms within 5.0 ms",
                    trace="traces/test_period.asc")
WARNED = TestResult("suites/test_value_domain.py::test_types[1800.02]", "object dictionary", "warning", "inferred",
                    None, "type 0 accepted [inferred: capabilities.tpdo_transmission_types]")
SKIPPED = [TestResult(f"suites/test_lss.py::test_x[{n}]", "LSS", "skipped",
                      message=f"not applicable: the profile declares no LSS identify ({n})") for n in range(3)]
CONTEXT = PageContext(
    custody=[("device snapshot: device-snapshot.json", False), ("could not restore 6003h: SDO abort", True)],
    deviations=[Deviation(f"quirk-{n}", f"deviation {n}", "manual §4.2", "CiA 406", n % 2) for n in range(46)],
    draft="draft profile: 2 assumptions unconfirmed", todo=["6004h access", "1017h default"],
    environment={"Python": "3.11.7", "SDO abort codes": "exact (--abort-codes)"})


def _positions(page: str, *needles: str) -> list[int]:
    positions = [page.find(n) for n in needles]
    assert -1 not in positions, [n for n, p in zip(needles, positions, strict=True) if p < 0]
    return positions


def test_first_screen_order_verdict_identity_areas_failures_warnings():
    page = render(_summary(PASSED, FAILED, WARNED, *SKIPPED), CONTEXT)
    positions = _positions(page, "id='verdict'", "id='identity'", "id='areas'", "id='failures'", "id='warnings'",
                           "id='custody'", "id='by-basis'", "id='deviations'", "id='skips'", "id='settings'")
    assert positions == sorted(positions)
    assert "g-banner g-fail" in page
    assert ">FAIL<" in page
    identity = page[positions[1]:positions[2]]
    assert _positions(identity, "serial", "revision", "vendor", "product", "name", "device type") == sorted(
        _positions(identity, "serial", "revision", "vendor", "product", "name", "device type"))
    assert "12345656 (0x00BC6138)" in identity
    assert "wachendorff-wdga-mt" in page
    assert "2026-11-26 06:30:41" in page
    failure = page[positions[3]:positions[4]]
    assert "test_period" in failure
    assert "expected 50 ms within 5.0 ms" in failure
    assert "CiA 301 §7.2.8.3.2.2" in failure
    assert "href='traces/test_period.asc'" in failure
    assert "href='traces/test_period.log'" in failure


def test_areas_in_reading_order_with_counts():
    page = render(_summary(PASSED, FAILED, WARNED, *SKIPPED))
    areas = page[page.index("id='areas'"):page.index("id='failures'")]
    names = ["identity", "working order", "object dictionary", "SDO", "NMT", "error control", "EMCY", "PDO",
             "store/restore", "LSS", "encoder function", "CAM"]
    assert _positions(areas, *(f"<td>{n}</td>" for n in names)) == sorted(_positions(areas, *(f"<td>{n}</td>"
                                                                                              for n in names)))
    assert "<td>LSS</td><td class='g-v-none'>NOT RUN</td><td class='n'>0</td><td class='n'>0</td>" \
           "<td class='n'>0</td><td class='n'>0</td><td class='n'>0</td><td class='n'>3</td>" in areas  # 3 out of scope
    assert "<td>error control</td><td class='g-v-fail'>FAIL</td><td class='n'>0</td><td class='n'>1</td>" in areas
    assert "<td>SDO</td><td class='g-v-none'>NOT RUN</td>" in areas  # an area without tests is shown, greyed


def test_deviations_skips_settings_folded_draft_and_alarms_visible():
    page = render(_summary(PASSED, *SKIPPED, restored=False), CONTEXT)
    for section in ("deviations", "skips", "settings", "by-basis", "custody"):
        assert f"<details id='{section}'>" in page
    deviations = page[page.index("<details id='deviations'>"):page.index("</details>", page.index("id='deviations'"))]
    assert deviations.count("<tr>") == 47
    assert "46; 23 relied on" in deviations
    assert "Out of scope (not applicable, not available, not selected): 3 tests, 1 reasons" in page  # one reason:
    # the parenthesis names the parameter
    assert "bench-3" in page
    assert "Ana" in page
    assert "pcan (from station bench.toml)" in page
    assert "3.11.7" in page
    # not given back: the alarm is shown unfolded, before the fold, and the banner says FAIL
    alarm = page.index("<div class='g-alarm'>could not restore 6003h")
    assert alarm < page.index("<details id='custody'>")
    assert "g-banner g-fail" in page
    assert "NOT given back" in page
    assert page.index("draft profile: 2 assumptions") < page.index("id='identity'")


def test_alarms_folded_when_device_given_back():
    page = render(_summary(PASSED, restored=True), PageContext(custody=[("a note", True)]))
    assert "<div class='g-alarm'>" not in page

HELD = TestResult("suites/test_nmt.py::test_operational", "NMT", "skipped", message="not testable: NMT start: 1001h = "
                  "01h (the device keeps an error)", skip_kind="not testable", hold="PERSISTENT_ERROR")


def test_checks_not_judged_shown_open_apart_from_the_scope():
    """What kept checks in scope from judging is open on the first screen; the scope is folded and declared."""
    summary = _summary(PASSED, HELD, *SKIPPED)
    summary.scope = {"power switch": "none: the power-cycle checks are out of scope"}
    page = render(summary)
    held = page.index("<details id='not-judged' open>")
    assert "NOT RUN" not in page[page.index("<td>NMT</td>"):page.index("</tr>", page.index("<td>NMT</td>"))]
    assert "1001h = 01h" in page[held:page.index("</details>", held)]
    assert "<details id='skips'>" in page
    assert "Out of scope" in page
    assert "none: the power-cycle checks are out of scope" in page[page.index("id='scope'"):]


def test_memory_not_as_found_is_shown_though_the_values_were_given_back():
    """Values given back, memory not (dut/store/boot_memory.py): the alarm unfolded, never "given back as found"."""
    summary = _summary(PASSED, restored=True)
    summary.device_memory = "the device reported no valid stored parameters when the run began"
    page = render(summary, PageContext(custody=[("MEMORY NOT AS FOUND: it stores now", True)]))
    assert "<div class='g-alarm'>MEMORY NOT AS FOUND: it stores now" in page
    assert "(values given back, memory NOT as found)" in page
    assert "given back as found)" not in page


@pytest.mark.parametrize(("results", "stopped", "css", "word"), [
    ((PASSED,), None, "g-pass", "PASS"),
    ((PASSED, WARNED), None, "g-warn", "PASS WITH WARNINGS"),
    ((PASSED,), "the device went silent", "g-none", "COULD NOT TEST"),
    ((), None, "g-none", "NOT RUN"),
    ((PASSED, HELD), None, "g-inc", "INCOMPLETE"),
])
def test_banner_colour_per_verdict(results, stopped, css, word):
    page = render(_summary(*results, stopped=stopped))
    assert f"g-banner {css}" in page
    assert f"<span class='g-word'>{word}</span>" in page
    assert "Failures: none" in page


def test_text_is_escaped():
    evil = TestResult("suites/test_sdo_protocol.py::test_x[<b>]", "SDO", "failed", message="expected <1> & got </pre>")
    page = render(_summary(evil))
    assert "expected &lt;1&gt; &amp; got &lt;/pre&gt;" in page
    assert "test_x[&lt;b&gt;]" in page


def test_skip_reason_key_drops_the_parameter():
    assert skip_reason_key("not applicable: no LSS (sub 2)") == "not applicable: no LSS"


def _fake_item(tmp_path: Path, policy: str) -> SimpleNamespace:
    """What settle_trace reads of a pytest item: its stash, the option, the evidence with a trace pair on disk."""
    trace = tmp_path / "traces" / "t.asc"
    trace.parent.mkdir(exist_ok=True)
    trace.write_text("asc")
    trace.with_suffix(".log").write_text("log")
    config = SimpleNamespace(stash=pytest.Stash(), getoption=lambda name, default=None: policy
                             if name == TRACE_OPTION else default)
    item = SimpleNamespace(stash=pytest.Stash(), config=config, funcargs={}, user_properties=[])
    item.stash[EVIDENCE] = Evidence(trace_path=trace)
    return item


def _phase(item, when: str, failed: bool = False) -> None:
    report = SimpleNamespace(when=when, failed=failed, outcome="failed" if failed else "passed", user_properties=[],
                             extras=[])
    reporting.attach_evidence(item, None, report)  # type: ignore[arg-type]


@pytest.mark.parametrize(("policy", "teardown_fails", "shared", "kept"), [
    ("failed", False, False, False), ("failed", True, False, True), ("all", False, False, True),
    ("failed", False, True, True)])  # shared: other verdicts rest on its frames (the periodic capture)
def test_trace_kept_by_policy_and_teardown_failure(tmp_path, policy, teardown_fails, shared, kept):
    item = _fake_item(tmp_path, policy)
    item.stash[EVIDENCE].keep_trace = shared
    trace = item.stash[EVIDENCE].trace_path
    _phase(item, "setup")
    _phase(item, "call")
    assert trace.exists()  # nothing is deleted before the last phase
    _phase(item, "teardown", failed=teardown_fails)
    assert trace.exists() == kept
    assert trace.with_suffix(".log").exists() == kept
    assert (item.stash[EVIDENCE].trace_path is not None) == kept


def _frames() -> list[can.Message]:
    return [can.Message(timestamp=1_700_000_000.0 + i / 1000, arbitration_id=0x581 + (i % 2) * 0x80,
                        data=bytes([0x43, 0x00, 0x10, 0x00, i, 0, 0, 0]), is_rx=bool(i % 3), is_remote_frame=i == 4,
                        dlc=8) for i in range(12)]


def test_held_trace_writes_what_the_live_writers_wrote(tmp_path):
    """A trace held in memory (plugin/bus_trace.py) writes the same ASC and candump files as python-can's writers
    fed frame by frame; the ASC header's date is when the trace began, not when it is written."""
    live = tmp_path / "live.asc"
    asc, log = can.ASCWriter(str(live)), can.CanutilsLogWriter(str(live.with_suffix(".log")))
    held = bus_trace.BusTrace(tmp_path / "traces" / "held.asc")
    for msg in _frames():
        asc.on_message_received(msg)
        log.on_message_received(msg)
        held.on_message_received(msg)
    asc.stop()
    log.stop()
    held.write()
    assert held.path.with_suffix(".log").read_text() == live.with_suffix(".log").read_text()
    live_lines, held_lines = live.read_text().splitlines(), held.path.read_text().splitlines()
    assert held_lines[1:] == live_lines[1:]
    assert held_lines[0] == "date " + asc._format_header_datetime(held.began)


def test_trace_written_only_when_kept_or_never_settled(tmp_path):
    """settle writes a kept trace and drops the rest; one never settled (its test stopped by Ctrl-C before its
    teardown report) is written at the session's end."""
    config = SimpleNamespace(stash=pytest.Stash())
    kept, dropped, stopped = (bus_trace.BusTrace(tmp_path / "traces" / f"{n}.asc") for n in ("k", "d", "s"))
    for trace in (kept, dropped, stopped):
        bus_trace.opened(config, trace)  # type: ignore[arg-type]
        for msg in _frames():
            trace.on_message_received(msg)
    bus_trace.settle(config, kept, keep=True)  # type: ignore[arg-type]
    bus_trace.settle(config, dropped, keep=False)  # type: ignore[arg-type]
    assert sorted(p.name for p in (tmp_path / "traces").iterdir()) == ["k.asc", "k.log"]
    bus_trace.write_unsettled(config)  # type: ignore[arg-type]
    assert sorted(p.name for p in (tmp_path / "traces").iterdir()) == ["k.asc", "k.log", "s.asc", "s.log"]
    assert kept.frames == dropped.frames == []  # settled: the frames are let go


@pytest.fixture(scope="module")
def fault_run(tmp_path_factory):
    """The heartbeat tests against the WDGA twin with a heartbeat 20 % slow: one failure, passes and skips."""
    folder = tmp_path_factory.mktemp("glance")
    completed = run_suite(folder, "--ec-profile", "wachendorff-wdga-mt", "--ec-sim-fault", "heartbeat_slow_20pct",
                          "-k", "heartbeat")[0]
    return folder / "report", completed


def test_end_to_end_banner_before_pytest_html_table(fault_run):
    folder, completed = fault_run
    assert completed.returncode == 1, completed.output[-3000:]
    page = (folder / "report.html").read_text(encoding="utf-8")
    banner, identity, areas, failures, table = _positions(
        page, "class='g-banner g-fail'", "id='identity'", "id='areas'", "id='failures'", 'id="results-table"')
    assert banner < identity < areas < failures < table
    assert "12345656" in page[identity:areas]
    assert "test_heartbeat_period_within_tolerance" in page[failures:table]
    assert "#environment-header,#environment" in page  # pytest-html's environment table hidden, folded in ours
    assert "&#x27;Skipped: " not in page
    assert "Skipped: " not in page.split('id="results-table"')[1]


def test_end_to_end_traces_only_for_the_failure(fault_run):
    folder, _ = fault_run
    traces = sorted(p.name for p in (folder / "traces").iterdir())
    assert traces == ["test_heartbeat_period_within_tolerance.asc", "test_heartbeat_period_within_tolerance.log"]
    asc = list(can.ASCReader(str(folder / "traces" / traces[0])))
    log = list(can.CanutilsLogReader(str(folder / "traces" / traces[1])))
    assert len(asc) == len(log) > 50  # the heartbeat capture (set up for this test) is in its trace
    summary = RunSummary.read(folder)
    kept = {r.nodeid.split("::")[-1]: r.trace for r in summary.results}
    assert kept["test_heartbeat_period_within_tolerance"] == "traces/test_heartbeat_period_within_tolerance.asc"
    assert all(trace is None for name, trace in kept.items() if name != "test_heartbeat_period_within_tolerance")
    skipped = [r for r in json.loads((folder / "run-summary.json").read_text())["results"] if r["outcome"] == "skipped"]
    assert skipped
    assert all(not r["message"].startswith(("(", "Skipped")) for r in skipped)


def test_end_to_end_report_folder_is_small(fault_run):
    folder, _ = fault_run
    size = sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())
    assert size < 500_000, f"report folder of an 11-test run: {size} bytes"


def test_trace_all_keeps_passed_traces(tmp_path):
    completed = run_suite(tmp_path, "--ec-profile", "wachendorff-wdga-mt", "-k", "test_heartbeat_frame_format",
                          "--ec-trace", "all")[0]
    assert completed.returncode == 0, completed.output[-3000:]
    traces = sorted(p.name for p in (tmp_path / "report" / "traces").iterdir())
    assert traces == ["test_heartbeat_frame_format.asc", "test_heartbeat_frame_format.log"]
    assert "traces/test_heartbeat_frame_format.log" in (tmp_path / "report" / "report.html").read_text()


def test_end_to_end_timing_plot_embedded_as_svg(fault_run):
    """The heartbeat period test (a timing test) carries its plot: an SVG data URI that decodes and parses, with
    the measurement's name as its title and one dot per sample."""
    folder, _ = fault_run
    page = (folder / "report.html").read_text(encoding="utf-8")
    plots = re.findall(r"data:image/svg\+xml;base64,([A-Za-z0-9+/=]+)", page)
    assert plots
    for plot in plots:
        root = ElementTree.fromstring(base64.b64decode(plot))
        assert root.findtext("{http://www.w3.org/2000/svg}title")
        assert len(list(root.iter("{http://www.w3.org/2000/svg}circle"))) >= 50
