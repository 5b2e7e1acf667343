"""The time budget of a run (issue 30): every wait for the device booked to what it waits for, the rest the
tester's; in run-summary.json, the report and the terminal."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import can

from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.link.time_budget import TimeBudget, difference
from encoder_conformance.dut.link.tracing_bus import TracingBus
from tests.suite_session import run_suite


def test_nested_waits_count_once_under_the_outer_booking():
    budget = TimeBudget()
    with budget.booking("boot-up"), budget.booking("answer"):
        time.sleep(0.02)  # stands in for a wait on the bus
    totals = budget.snapshot()
    assert totals["boot-up"] >= 0.02
    assert totals["answer"] == 0


def test_the_testers_own_cpu_inside_a_wait_is_told_apart():
    """What the tester's process computes while a wait is booked is owed by the category's meaning, but shown
    beside it as the tester's CPU; a wait that only sleeps costs it next to nothing."""
    budget = TimeBudget()
    with budget.booking("sdo"):
        deadline = time.process_time() + 0.03
        while time.process_time() < deadline:  # stands in for the SDO client's own work
            pass
    with budget.booking("silence"):
        time.sleep(0.03)
    cpu, totals = budget.cpu_snapshot(), budget.snapshot()
    assert 0.03 <= cpu["sdo"] <= totals["sdo"] + 0.01
    assert cpu["silence"] < 0.02 < totals["silence"]


def test_waits_of_other_threads_are_not_booked():
    """A background capture's waits overlap the test's own: only the test thread books."""
    budget = TimeBudget()

    def elsewhere() -> None:
        with budget.booking("silence"):
            time.sleep(0.01)

    worker = threading.Thread(target=elsewhere)
    worker.start()
    worker.join()
    assert budget.snapshot()["silence"] == 0


def test_an_answer_wait_that_times_out_is_a_silence():
    from encoder_conformance.dut.link import time_budget

    before = time_budget.BUDGET.snapshot()
    assert FrameLog().wait_for(lambda m: True, 0.03) is None
    booked = difference(time_budget.BUDGET.snapshot(), before)
    assert booked.keys() == {"silence"}
    assert booked["silence"] >= 0.03


def test_a_frame_handed_to_the_bus_is_traffic_and_an_sdo_transfer_books_its_own_once():
    """A raw frame's send is booked as ``send`` (the interface's time); inside a transfer it is the transfer's."""
    from encoder_conformance.dut.link import time_budget

    log = FrameLog()
    bus = TracingBus(can.interface.Bus(interface="virtual", channel="budget-send"), log)
    try:
        before = time_budget.BUDGET.snapshot()
        bus.send(can.Message(arbitration_id=0x80, data=b"", is_extended_id=False))
        assert difference(time_budget.BUDGET.snapshot(), before).keys() == {"send"}
        before = time_budget.BUDGET.snapshot()
        with time_budget.BUDGET.booking("sdo"):
            bus.send(can.Message(arbitration_id=0x605, data=bytes(8), is_extended_id=False))
        assert difference(time_budget.BUDGET.snapshot(), before).keys() == {"sdo"}
    finally:
        bus.shutdown()


def test_a_run_reports_its_budget(tmp_path: Path):
    completed, _ = run_suite(tmp_path, "--ec-profile", "waycon-sx", "-k", "heartbeat_period or identity")
    assert completed.returncode == 0, completed.output[-2000:]
    budget = json.loads((tmp_path / "report" / "run-summary.json").read_text(encoding="utf-8"))["time_budget"]
    assert 0 < budget["owed_s"] < budget["wall_s"]
    assert abs(budget["wall_s"] - budget["owed_s"] - budget["tester_s"]) < 0.01
    assert abs(budget["wall_s"] - budget["outside_tests_s"] - budget["inside_tests_s"]) < 0.01
    assert 0 <= budget["tester_share_inside"] <= 1
    assert budget["host_wait_s"] is None or 0 <= budget["host_wait_s"] < budget["wall_s"]
    assert 0 < budget["startup_s"] <= budget["outside_tests_s"], "start-up to the first test: outside the tests"
    assert 0 < budget["owed_tester_cpu_s"] < budget["owed_s"]
    assert budget["owed_tester_cpu"].keys() <= budget["owed"].keys()
    sdo = next(w for w in budget["windows"] if w["name"] == "sdo_response_max_ms")
    assert sdo["seconds"] > 0
    assert "measured SDO p99" in sdo["source"], "each window names the figure it came from"
    assert budget["answer_times"]["sdo"]["samples"] == 30
    assert budget["owed"]["periodic"] > 0.5, "the heartbeat capture is owed to the device"
    heartbeat = next(t for t in budget["costliest"] if "heartbeat_period" in t["nodeid"])
    assert heartbeat["why"].startswith("periodic")
    assert "time budget:" in completed.output
    assert "s to the first test" in completed.output
    html = (tmp_path / "report" / "report.html").read_text(encoding="utf-8")
    assert "id='time-budget'" in html
    assert "id='silence-windows'" in html, "the report shows each window and its source"
    assert "Measured at the start of the run" in html
