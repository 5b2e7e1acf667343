"""Late-frame attribution (issue 42, item 2; dut/link/late_frames.py, plugin/late_frames.py): a frame after the window
that proved it absent is attributed to its request or state, never a frame a later request or state change explains;
a late frame while the host was late is inconclusive; the twin faults made for it end FAIL, the twin without them
shows no late frame."""

from __future__ import annotations

import json
import time

import can
import pytest

from encoder_conformance.cia.cia301 import HEARTBEAT_BASE, NMT_COB_ID, SDO_REQUEST_BASE, SDO_RESPONSE_BASE
from encoder_conformance.dut.link import late_frames
from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.link.late_frames import LateLedger, Owner
from encoder_conformance.dut.sdo.sdo_frames import upload_request
from encoder_conformance.runs.fault_matrix import run_suite

NODE = 5
TPDO = 0x180 + NODE
R = upload_request(0x1000, 0)  # the request that must stay unanswered
ANSWER_R = bytes([0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00])
L_OTHER = upload_request(0x1018, 1)
ANSWER_L_OTHER = bytes([0x43, 0x18, 0x10, 0x01, 0x01, 0x00, 0x00, 0x00])


def rx(cob_id: int, data: bytes, late_by_s: float = 0.0) -> can.Message:
    """A device frame, stamped ``late_by_s`` before it reaches the ledger (its delivery lag)."""
    return can.Message(timestamp=time.time() - late_by_s, arbitration_id=cob_id, data=data, is_rx=True)


def tx(cob_id: int, data: bytes) -> can.Message:
    return can.Message(timestamp=time.time(), arbitration_id=cob_id, data=data, is_rx=False)


@pytest.fixture
def ledger() -> LateLedger:
    Owner.nodeid = "suites/test_x.py::test_owner"
    ledger = LateLedger()
    ledger.close_sdo(NODE, R, "SDO request in stopped", "CiA 301 §7.3.2")
    return ledger


def feed(ledger: LateLedger, *frames: can.Message) -> list[late_frames.LateFrame]:
    for frame in frames:
        ledger.on_frame(frame)
    return ledger.judged()



def test_the_margin_is_the_unmeasured_windows_own():
    from encoder_conformance.dut.link.windows import UNMEASURED_MARGIN_S
    assert late_frames.HOST_TOLERANCE_MS == UNMEASURED_MARGIN_S * 1000


def test_an_answer_after_the_window_is_attributed_to_its_request(ledger):
    found = feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))
    assert [late.verdict for late in found] == ["fail"]
    assert found[0].window.owner == "suites/test_x.py::test_owner"
    text = found[0].describe()
    assert "40 00 10 00" in text
    assert "CiA 301 §7.3.2" in text
    assert "inference" in text


def test_the_answer_to_a_later_request_of_the_same_object_is_not_attributed(ledger):
    found = feed(ledger, tx(SDO_REQUEST_BASE + NODE, R), rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))
    assert found == []


def test_a_second_reply_beyond_the_later_requests_is_attributed(ledger):
    found = feed(ledger, tx(SDO_REQUEST_BASE + NODE, R), rx(SDO_RESPONSE_BASE + NODE, ANSWER_R),
                 rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))
    assert len(found) == 1


def test_a_later_request_of_another_object_excuses_only_its_own_answer(ledger):
    assert feed(ledger, tx(SDO_REQUEST_BASE + NODE, L_OTHER), rx(SDO_RESPONSE_BASE + NODE, ANSWER_L_OTHER)) == []
    assert len(feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))) == 1


def test_a_later_request_may_draw_an_answer_and_an_abort(ledger):
    """A server may abort a transfer after confirming its initiate (its own time-out): not a surplus."""
    abort = bytes([0x80, 0x00, 0x10, 0x00, 0x00, 0x00, 0x04, 0x05])
    assert feed(ledger, tx(SDO_REQUEST_BASE + NODE, R), rx(SDO_RESPONSE_BASE + NODE, ANSWER_R),
                rx(SDO_RESPONSE_BASE + NODE, abort)) == []
    assert len(feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))) == 1


def test_another_masters_request_excuses_like_the_testers(ledger):
    assert feed(ledger, rx(SDO_REQUEST_BASE + NODE, R), rx(SDO_RESPONSE_BASE + NODE, ANSWER_R)) == []


def test_a_block_transfer_ends_the_window(ledger):
    block_upload = bytes([0xA4, 0x00, 0x10, 0x00, 0x7F, 0x00, 0x00, 0x00])
    assert feed(ledger, tx(SDO_REQUEST_BASE + NODE, block_upload), rx(SDO_RESPONSE_BASE + NODE, ANSWER_R)) == []


def test_nothing_is_attributed_beyond_the_horizon(ledger, monkeypatch):
    monkeypatch.setattr(late_frames, "HORIZON_S", 0.0)
    assert feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R)) == []
    assert not ledger.watching


def test_a_late_frame_while_the_host_was_late_is_inconclusive(ledger):
    found = feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R, late_by_s=0.2))
    assert [late.verdict for late in found] == ["inconclusive"]
    assert "inconclusive" in found[0].describe()
    assert "delivered 200" in found[0].describe()


def test_a_host_later_than_the_margin_but_not_as_late_as_the_frame_does_not_excuse_it(ledger):
    ledger._windows[0].closed_at -= 0.3  # the window closed 300 ms before the answer comes
    assert [late.verdict for late in feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R, late_by_s=0.08))] == ["fail"]


def test_the_twins_own_lateness_makes_it_inconclusive(ledger):
    ledger.twin = lambda since: [(since + 0.05, 80.0)]  # around the window: the twin ran 80 ms late
    assert [late.verdict for late in feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))] == ["inconclusive"]


def test_a_state_window_runs_from_the_heartbeat_to_the_next_nmt_command():
    ledger = LateLedger()
    ledger.open_state(NODE, "stop", lambda m: m.arbitration_id == TPDO, f"TPDO {TPDO:03X}h", "CiA 301 §7.3.2.2")
    heartbeat = HEARTBEAT_BASE + NODE
    # before the device reports stopped it may still be carrying out the command: not attributed
    assert feed(ledger, rx(heartbeat, b"\x05"), rx(TPDO, b"\x01")) == []
    found = feed(ledger, rx(heartbeat, b"\x04"), rx(TPDO, b"\x02"))
    assert len(found) == 1
    assert "heartbeat reported the state" in found[0].describe()
    # the tester's next NMT command (start): what follows may be the new state's
    assert feed(ledger, tx(NMT_COB_ID, bytes([0x01, NODE])), rx(TPDO, b"\x03")) == []
    assert not ledger.watching


def test_a_client_abort_draws_no_reply_that_could_excuse_a_late_one(ledger):
    """An abort is unconfirmed (CiA 301 §7.2.4.3.17): a reply after it is still the surplus of the closed request."""
    abort = bytes([0x80, 0x00, 0x10, 0x00, 0x00, 0x00, 0x00, 0x08])
    found = feed(ledger, tx(SDO_REQUEST_BASE + NODE, abort), rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))
    assert len(found) == 1


def test_a_frame_is_charged_to_one_window_only(ledger):
    Owner.nodeid = "suites/test_x.py::test_later"
    ledger.close_sdo(NODE, bytes([0x80, 0x18, 0x10, 0x01, 0, 0, 0, 8]), "the client's abort", "CiA 301 §7.2.4.3.17")
    found = feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))
    assert [late.window.owner for late in found] == ["suites/test_x.py::test_owner"]  # the oldest that claims it


def test_a_forbidden_frame_is_charged_until_what_may_allow_it_again():
    """``forbid``: a SYNC after 1006h = 0 until 1006h is written other than 0 (or the node restarts)."""
    ledger = LateLedger()
    sync = lambda m: m.arbitration_id == 0x80  # noqa: E731
    until = lambda m: late_frames.writes(NODE, 0x1006, 0, unless=bytes(4))(m) or late_frames.restarts(NODE)(m)  # noqa: E731
    ledger.forbid(sync, "a SYNC", "1006h = 0", "CiA 301 §7.5.2.6", until)
    assert len(feed(ledger, tx(SDO_REQUEST_BASE + NODE, upload_request(0x1006, 0)), rx(0x80, b""))) == 1
    zero = bytes([0x23, 0x06, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00])  # written 0 again: still forbidden
    assert len(feed(ledger, tx(SDO_REQUEST_BASE + NODE, zero), rx(0x80, b""))) == 1
    write = bytes([0x23, 0x06, 0x10, 0x00, 0x10, 0x27, 0x00, 0x00])
    assert feed(ledger, tx(SDO_REQUEST_BASE + NODE, write), rx(0x80, b"")) == []
    assert not ledger.watching


@pytest.mark.parametrize("restart", [tx(NMT_COB_ID, bytes([0x81, NODE])), tx(NMT_COB_ID, bytes([0x82, 0])),
                                     rx(HEARTBEAT_BASE + NODE, b"\x00")], ids=["reset node", "reset comm", "boot-up"])
def test_a_restart_ends_a_forbidding_window(restart):
    ledger = LateLedger()
    heartbeat = lambda m: m.arbitration_id == HEARTBEAT_BASE + NODE and bytes(m.data) != b"\x00"  # noqa: E731
    ledger.forbid(heartbeat, "a heartbeat", "1017h = 0", "CiA 301 §7.2.8.3.2.2", late_frames.restarts(NODE))
    assert feed(ledger, restart, rx(HEARTBEAT_BASE + NODE, b"\x7f")) == []


def test_an_inconclusive_late_frame_makes_its_area_pass_with_warnings(ledger):
    from encoder_conformance.plugin.late_frames import UNSURE, _unsure
    from encoder_conformance.run_summary import AreaVerdict, RunSummary

    Owner.nodeid = "suites/test_nmt.py::test_no_sdo_in_stopped"
    ledger.close_sdo(NODE, R, "SDO request in stopped", "CiA 301 §7.3.2.2")
    found = feed(ledger, rx(SDO_RESPONSE_BASE + NODE, ANSWER_R, late_by_s=0.2))
    summary = RunSummary("run", "2026-12-07T00:00:00+00:00", "p", "0")
    for late in found * 2:
        _unsure(summary, late)
    assert [r.nodeid for r in summary.results] == [UNSURE + "suites/test_x.py::test_owner"]
    area = AreaVerdict("NMT")
    area.passed = 1
    area.count(summary.results[0])
    assert area.verdict == "PASS WITH WARNINGS"


def test_judged_takes_each_late_frame_once_and_by_owner(ledger):
    ledger.on_frame(rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))
    assert ledger.judged("suites/test_x.py::test_other") == []
    assert len(ledger.judged("suites/test_x.py::test_owner")) == 1
    assert ledger.judged() == []


def test_the_frame_log_feeds_the_ledger():
    log = FrameLog()
    Owner.nodeid = "suites/test_x.py::test_owner"
    log.late.close_sdo(NODE, R, "SDO request in stopped", "CiA 301 §7.3.2")
    log.record_sent(can.Message(arbitration_id=SDO_REQUEST_BASE + NODE, data=L_OTHER))
    log.on_message_received(rx(SDO_RESPONSE_BASE + NODE, ANSWER_L_OTHER))
    log.on_message_received(rx(SDO_RESPONSE_BASE + NODE, ANSWER_R))
    assert len(log.late.judged()) == 1


# -- end to end: the twin faults made for the short windows, and the twin without them --------------------------------
PROFILE = "wachendorff-wdga-mt"
SDO_SELECT = "test_no_sdo_in_stopped or test_no_pdo_outside_operational"
TPDO_SELECT = "test_tpdo_silent_after_leaving_operational"  # the fault is made for test_pdo_comm


def _summary(tmp_path, name: str) -> dict:
    return json.loads((tmp_path / name / "run-summary.json").read_text(encoding="utf-8"))


def test_an_sdo_answer_in_stopped_after_the_window_fails_the_run(tmp_path):
    """The owner had reported when the answer came: a run-level check names it (JUnit, run-summary.json)."""
    result = run_suite(PROFILE, "sdo_late_in_stopped", tmp_path, SDO_SELECT, targeted=True)
    check = "late_frames::late frame: suites/test_nmt.py::test_no_sdo_in_stopped"
    assert result.outcomes[check] == "failed"
    assert result.outcomes["test_nmt::test_no_sdo_in_stopped"] == "passed"  # its own window saw nothing
    summary = _summary(tmp_path, "sdo_late_in_stopped")
    assert summary["overall"] == "FAIL"
    assert result.returncode == 1
    assert any("test_no_sdo_in_stopped" in line and "FAIL" in line for line in summary["late_frames"])


def test_a_tpdo_after_leaving_operational_fails_its_test(tmp_path):
    """The owner was still running: it fails itself (its own windows, after the settle time, saw nothing)."""
    result = run_suite(PROFILE, "tpdo_late_after_leaving_operational", tmp_path, TPDO_SELECT, targeted=True)
    failed = {name for name, outcome in result.outcomes.items() if outcome == "failed"}
    assert any(name.startswith("test_pdo_comm::test_tpdo_silent_after_leaving_operational") for name in failed)


@pytest.mark.parametrize("select", [SDO_SELECT, TPDO_SELECT], ids=["sdo", "tpdo"])
def test_the_twin_without_faults_shows_no_late_frame(tmp_path, select):
    result = run_suite(PROFILE, None, tmp_path, select)
    assert not {n for n, o in result.outcomes.items() if o not in ("passed", "skipped")}, result.outcomes
    assert _summary(tmp_path, "no-fault")["late_frames"] == []
