"""Outcomes that say what happened (issue 26, shared DESIGN §8): FAIL, COULD NOT TEST and INTERNAL ERROR, never mixed.

- a device that goes silent after a fuzz frame fails that test, naming the last frames sent: exit 1, the other
  tests not run, the device still given back;
- replies that break CiA 301 at the start-up check, with no other client on the bus: exit 1 with the clause;
- an exception that is no finding about the device (injected by a tiny plugin): exit 3, outcome "error", outside
  every area verdict; beside a device failure the run still exits 1.
Each is a real pytest session of the suites against the twin.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import can
import pytest

from encoder_conformance.dut.sdo import startup_frames
from encoder_conformance.errors import BusLostError, DutLostError
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.paths import CONTENT_ROOT, SUITES_DIR
from encoder_conformance.plugin.outcomes import is_device_finding
from encoder_conformance.run_summary import INTERNAL_ERROR_TEXT, RunSummary, TestResult
from encoder_conformance.runs.suite_runner import run_pytest

PROFILE = "wachendorff-wdga-mt"
INJECTED = "test_vendor_id_matches_profile"
PLUGIN = f'''
import pytest

@pytest.hookimpl(tryfirst=True)
def pytest_runtest_call(item):
    if item.name == "{INJECTED}":
        raise AttributeError("'NoneType' object has no attribute 'code' (injected by tests/test_run_outcomes.py)")
'''


def _suite(module: str, folder: Path, *extra: str) -> tuple[int, RunSummary, str]:
    """A run of one suite module against the twin: exit code, run summary, output."""
    command = [str(SUITES_DIR / f"{module}.py"), "-q", "-p", "no:cacheprovider", "--ec-profile", PROFILE,
               "--ec-report-dir", str(folder), "--ec-history", "off", *extra]
    env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
    result = run_pytest(command, CONTENT_ROOT, folder / "pytest-output.txt", timeout=300, env=env)
    return result.returncode, RunSummary.read(folder), result.output


def _with_plugin(module: str, folder: Path, plugin_dir: Path, *extra: str) -> tuple[int, RunSummary, str]:
    """The same run as its own interpreter, with the injecting plugin importable (-p)."""
    (plugin_dir / "inject_internal_error.py").write_text(PLUGIN, encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(plugin_dir), env.get("PYTHONPATH")]))
    command = [sys.executable, "-m", "pytest", str(SUITES_DIR / f"{module}.py"), "-q", "-p", "no:cacheprovider",
               "-p", "inject_internal_error", "--ec-profile", PROFILE, "--ec-report-dir", str(folder),
               "--ec-history", "off", *extra]
    done = subprocess.run(command, cwd=CONTENT_ROOT, env=env, capture_output=True, text=True, timeout=300)
    return done.returncode, RunSummary.read(folder), done.stdout + done.stderr


def _result(summary: RunSummary, name: str) -> TestResult:
    return next(r for r in summary.results if r.nodeid.endswith(f"::{name}") or r.nodeid == name)


def test_device_silent_after_a_fuzz_frame_fails_that_test(tmp_path):
    code, summary, output = _suite("test_sdo_fuzz", tmp_path, "--ec-sim-fault", "silent_after_reserved_command")
    assert code == RunExit.NON_CONFORMANT, output[-3000:]
    failed = _result(summary, "test_reserved_command_specifiers_abort")
    assert failed.outcome == "failed"
    assert failed.area == "SDO"
    assert "the device stopped answering" in failed.message
    assert "the last frames sent before" in failed.message
    sent = failed.message.split("the last frames sent before")[1]
    assert any(f"Tx 67F [8] {b:02X}" in sent for b in range(0xE0, 0x100)), "the reserved command is not named"
    assert summary.overall == "FAIL"
    assert summary.could_not_test is None
    assert summary.device_failed
    assert summary.not_run >= 1, "the tests after it are counted as not run"
    restore = json.loads((tmp_path / "device-restore.json").read_text(encoding="utf-8"))
    assert restore["done"], "the device's custody was not attempted to the end"
    assert summary.device_restored, "the device (back after NMT reset node) was not given back"


def test_wrong_multiplexer_fails_at_the_start_up_check(tmp_path):
    code, summary, output = _suite("test_sdo_fuzz", tmp_path, "--ec-sim-fault", "sdo_reply_wrong_mux")
    assert code == RunExit.NON_CONFORMANT, output[-3000:]
    check = _result(summary, "start-up check")
    assert check.outcome == "failed"
    assert check.basis == "cia"
    assert "CiA 301 v4.2.0 §7.2.4.3.6" in (check.source or "")
    assert "multiplexer 1000h.01" in check.message
    assert "only this tester's requests" in check.message
    assert summary.overall == "FAIL"
    assert summary.could_not_test is None
    assert [a.area for a in summary.areas() if a.verdict == "FAIL"] == ["SDO"]


def test_internal_error_exits_3_outside_every_area_verdict(tmp_path):
    code, summary, output = _with_plugin("test_identity", tmp_path / "run", tmp_path)
    assert code == RunExit.INTERNAL_ERROR, output[-3000:]
    error = _result(summary, INJECTED)
    assert error.outcome == "error"
    assert error.message.startswith(INTERNAL_ERROR_TEXT)
    assert error.basis is None
    assert all(area.failed == 0 for area in summary.areas()), "an internal error counted against an area"
    assert summary.overall == "INTERNAL ERROR"
    assert "internal error" in output
    page = (tmp_path / "run" / "report.html").read_text(encoding="utf-8")
    assert "Internal errors of the tool (1): please report them" in page
    case = next(c for c in ET.parse(tmp_path / "run" / "junit.xml").getroot().iter("testcase")
                if c.get("name") == INJECTED)
    assert ("verdict", "internal error") in {(p.get("name"), p.get("value")) for p in case.iter("property")}
    assert case.find("error") is not None, "JUnit: no <error> for the tool's internal error"
    assert case.find("failure") is None, "JUnit: the tool's internal error shown as a failure of the device"


def test_internal_error_beside_a_device_failure_exits_1(tmp_path):
    code, summary, output = _with_plugin("test_identity", tmp_path / "run", tmp_path,
                                         "--ec-sim-fault", "serial_mismatch")
    assert code == RunExit.NON_CONFORMANT, output[-3000:]
    assert _result(summary, INJECTED).outcome == "error"
    assert summary.overall == "FAIL"


@pytest.mark.parametrize(("exc", "finding"), [
    (AssertionError("x"), True), (DutLostError("silent"), True), (BusLostError("gone"), False),
    (AttributeError("code"), False), (TypeError("x"), False), (KeyError("x"), False), (NameError("x"), False),
    (ExceptionGroup("two", [AssertionError("a"), AssertionError("b")]), True),
    (ExceptionGroup("mixed", [AssertionError("a"), AttributeError("b")]), False),
])
def test_which_exceptions_are_findings_about_the_device(exc, finding):
    assert is_device_finding(exc) is finding


def test_pytest_fail_and_canopen_errors_are_findings():
    from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError
    assert is_device_finding(pytest.fail.Exception("verdict"))
    assert is_device_finding(SdoAbortedError(0x06020000))
    assert is_device_finding(SdoCommunicationError("no response"))


def _frame(cob_id: int, data: str, rx: bool) -> can.Message:
    payload = bytes.fromhex(data)
    return can.Message(arbitration_id=cob_id, data=payload, dlc=len(payload), is_extended_id=False, is_rx=rx)


def test_start_up_replies_with_another_client_on_the_bus_are_not_judged():
    frames = [_frame(0x605, "40 00 10 00 00 00 00 00", False), _frame(0x585, "43 00 10 01 96 01 02 00", True)]
    alone = startup_frames.judge(frames, 5)
    assert alone.broken
    assert not alone.other_client
    assert "§7.2.4.3.6" in alone.clauses
    shared = startup_frames.judge([_frame(0x605, "40 08 10 00 00 00 00 00", True), *frames], 5)
    assert shared.other_client, "another client's request must be seen"
    short = startup_frames.judge([frames[0], _frame(0x585, "43 00 10 00 96 01", True)], 5)
    assert [clause for _, clause in short.broken] == [startup_frames.DLC_CLAUSE]


def test_a_late_answer_to_a_request_given_up_on_is_not_a_broken_reply():
    """On a loaded machine the tester may time out and send its next request before the device answers: the
    late answer names the earlier request's multiplexer. Only a reply to a request that was answered
    meanwhile, or to the current one, is judged."""
    gave_up = [_frame(0x605, "40 03 18 05 00 00 00 00", False), _frame(0x605, "40 00 10 00 00 00 00 00", False),
               _frame(0x585, "4B 03 18 05 FF 00 00 00", True), _frame(0x585, "43 00 10 00 96 01 02 00", True)]
    assert not startup_frames.judge(gave_up, 5).broken
    answered_then_wrong = [_frame(0x605, "40 03 18 05 00 00 00 00", False),
                           _frame(0x585, "4B 03 18 05 FF 00 00 00", True),
                           _frame(0x605, "40 00 10 00 00 00 00 00", False),
                           _frame(0x585, "4B 03 18 05 FF 00 00 00", True)]
    assert [clause for _, clause in startup_frames.judge(answered_then_wrong, 5).broken] == [
        startup_frames.MUX_CLAUSES[2]]
