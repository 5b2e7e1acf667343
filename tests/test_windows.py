"""Silence windows from what the device shows (issue 42, item 1): SDO round trips measured at the start of a run,
each window the largest of FACTOR x the measured p99, the host's lateness and a documented bound (never less than a
manual promises; a suite default is no floor), an unmeasured kind its profile figure plus the tester's measured
part, every window with its source; the profile says which timing figures a manual documents."""

from __future__ import annotations

import pydantic
import pytest

from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link.answer_times import SDO_SAMPLES, AnswerTimes, measure_sdo
from encoder_conformance.dut.link.latency_probe import HostLatency
from encoder_conformance.dut.link.windows import (
    FACTOR,
    MIN_OBSERVED,
    SILENCE_FIGURES,
    UNMEASURED_MARGIN_S,
    Windows,
)
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.schema import Timing
from tests import sim_rig

rig = sim_rig.rig  # the shared simulator fixture


def _times(p99_ms: float, host_ms: float = 0.1, twin_ms: float | None = None) -> AnswerTimes:
    seen = tuple([p99_ms / 2] * 28 + [p99_ms, p99_ms])
    return AnswerTimes("SDO", seen, seen, HostLatency(10, host_ms, host_ms, (), twin_ms))


def test_before_the_measurement_a_window_is_the_profile_figure_plus_the_named_margin():
    windows = Windows(timing=Timing(bootup_max_ms=1000, sdo_response_max_ms=100))
    window = windows.silence("sdo_response_max_ms")
    assert window.seconds == pytest.approx(0.1 + UNMEASURED_MARGIN_S)
    assert "no measurement" in window.source
    assert "suite default" in window.source


def test_a_measured_sdo_window_is_factor_times_p99_and_a_suite_default_is_no_floor():
    windows = Windows(timing=Timing(bootup_max_ms=1000, sdo_response_max_ms=100))
    windows.measured(_times(0.8))
    window = windows.silence("sdo_response_max_ms")
    assert window.seconds == pytest.approx(FACTOR * 0.8 / 1000)
    assert "is no floor" in window.source
    assert "p99 0.80 ms" in window.source


def test_a_documented_bound_is_never_waited_less():
    windows = Windows(timing=Timing(bootup_max_ms=1000, sdo_response_max_ms=20,
                             documented={"sdo_response_max_ms": "M §5.3.2"}))
    windows.measured(_times(0.5))
    window = windows.silence("sdo_response_max_ms")
    assert window.seconds == pytest.approx(0.020)
    assert "documented floor 20 ms (M §5.3.2)" in window.source


def test_the_host_lateness_wins_where_it_is_larger_the_twin_s_included():
    windows = Windows(timing=Timing(bootup_max_ms=1000, sdo_response_max_ms=1))
    windows.measured(_times(0.5, host_ms=3.0, twin_ms=12.0))
    assert windows.silence_s("sdo_response_max_ms") == pytest.approx(0.012)


def test_an_unmeasured_kind_is_its_figure_plus_the_tester_s_measured_part_and_appears_in_the_evidence():
    windows = Windows(timing=Timing(bootup_max_ms=1000, sdo_response_max_ms=1))
    windows.measured(_times(0.5))
    window = windows.silence("pdo_response_max_ms")
    assert window.seconds == pytest.approx((10 + FACTOR * 0.5) / 1000)
    assert "not measured" in window.source
    assert [w["name"] for w in windows.evidence()] == sorted(SILENCE_FIGURES)


def test_a_measured_window_is_used_as_measured_shorter_than_before_measurement():
    """No hold: once measured, a window may be shorter than its figure plus the unmeasured margin (every wait for a
    frame that must come uses the answer window), and a measured rule above it counts too."""
    windows = Windows(Timing(bootup_max_ms=1000, sdo_response_max_ms=1))
    windows.measured(_times(0.5, host_ms=3.0, twin_ms=80.0))
    assert windows.silence_s("sdo_response_max_ms") == pytest.approx(0.080)  # the twin's lateness
    windows = Windows(Timing(bootup_max_ms=1000, sdo_response_max_ms=1))
    windows.measured(_times(0.5))
    window = windows.silence("sdo_response_max_ms")
    assert window.seconds == pytest.approx(FACTOR * 0.5 / 1000)
    assert window.seconds < 0.001 + UNMEASURED_MARGIN_S
    assert "held" not in window.source


def test_documented_names_only_timing_figures():
    with pytest.raises(pydantic.ValidationError, match="names no timing figure: sdo_answer_ms"):
        Timing(bootup_max_ms=1000, sdo_response_max_ms=1, documented={"sdo_answer_ms": "M §1"})


def test_the_wdga_profile_documents_its_sdo_response_time_and_nothing_else():
    timing = load_profile("wachendorff-wdga-mt").profile.timing
    assert set(timing.documented) == {"sdo_response_max_ms"}
    assert "5.3.2" in timing.documented["sdo_response_max_ms"]


def test_the_start_measurement_takes_its_round_trips_from_the_twin(rig):
    profile = load_profile("wachendorff-wdga-mt").profile
    node, _ = rig.boot(profile)
    dut = DeviceUnderTest(rig.network, rig.log, profile, node.node_id)
    times = measure_sdo(dut)
    assert times is not None
    assert len(times.seen_ms) == SDO_SAMPLES
    assert times.unanswered == 0
    assert 0 < times.p50_ms <= times.p99_ms <= times.max_ms
    assert len(times.stamped_ms) == SDO_SAMPLES
    evidence = times.evidence()
    assert evidence["samples"] == SDO_SAMPLES
    assert evidence["twin_late_ms"] is None
    dut.windows.measured(times)
    assert dut.sdo_silence_s >= profile.timing.sdo_response_max_ms / 1000  # the manual's 1 ms, at least


def test_a_kind_the_run_observes_is_sized_from_its_answers_once_enough_came():
    windows = Windows(timing=Timing(bootup_max_ms=1000, sdo_response_max_ms=1))
    windows.measured(_times(0.5))
    for _ in range(MIN_OBSERVED - 1):
        windows.observe("lss_response_ms", 2.0)
    assert windows.silence_s("lss_response_ms") == pytest.approx((50 + FACTOR * 0.5) / 1000)
    windows.observe("lss_response_ms", 2.0)
    window = windows.silence("lss_response_ms")
    assert window.seconds == pytest.approx(FACTOR * 2.0 / 1000)
    assert f"LSS ({MIN_OBSERVED} answers in the run)" in window.source


def test_a_device_that_stops_answering_gives_no_measurement_and_costs_only_half_the_time_outs(rig):
    profile = load_profile("wachendorff-wdga-mt").profile
    node, _ = rig.boot(profile)
    dut = DeviceUnderTest(rig.network, rig.log, profile, node.node_id)
    node.power_off()
    mark = rig.log.mark()
    assert measure_sdo(dut, samples=4) is None
    requests = rig.log.since(mark, lambda m: not m.is_rx and m.arbitration_id == 0x600 + node.node_id)
    assert len(requests) == 2, "it stops once half the round trips went unanswered"
    assert dut.windows.silence("sdo_response_max_ms").source.endswith("(no measurement)")
