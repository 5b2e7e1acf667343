"""Error control: node guarding and heartbeat as the profile says they combine.

CiA 301 §7.2.8.3.1 keeps guard time (100Ch) and producer heartbeat time (1017h) independent.
Devices that make them exclusive (quirk ``guarding_heartbeat_exclusive``, e.g. FAULHABER MC
3.8.2.1/3.8.3) are checked against their own documented rule.
"""

from __future__ import annotations

import pytest

from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.plugin.suite_helpers import assert_abort, documented_quirk
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("CiA 301 §7.2.8.3.1 (error control); profile quirk guarding_heartbeat_exclusive"),
              pytest.mark.requires("node_guarding"), pytest.mark.requires("heartbeat_producer")]

GUARD_TIME_MS = 100


@pytest.fixture
def exclusion(dut, evidence):
    """The (producer, guard time, abort code) of the profile's exclusivity quirk."""
    params = documented_quirk(dut, fx.GuardingHeartbeatExclusive, evidence, "guarding and heartbeat are independent")
    return params.producer_object, params.guard_time_object, params.guard_time_write_while_producer_abort


def _u16(value: int) -> bytes:
    return value.to_bytes(2, "little")


def test_heartbeat_producer_switches_guarding_off(dut, exclusion, settings_journal, evidence):
    """With a guard time set, writing a producer heartbeat time > 0 sets the guard time to 0."""
    producer, guard_time, _ = exclusion
    period = dut.profile.timing.heartbeat_test_period_ms
    settings_journal.write(producer, 0, _u16(0))
    settings_journal.write(guard_time, 0, _u16(GUARD_TIME_MS))
    assert dut.read_uint(guard_time, 0) == GUARD_TIME_MS, f"{guard_time:04X}h did not take {GUARD_TIME_MS} ms"
    settings_journal.write(producer, 0, _u16(period))
    observed = dut.read_uint(guard_time, 0)
    evidence.measure(f"{guard_time:04X}h after {producer:04X}h = {period} ms", observed, "ms", 0, 0)
    assert observed == 0, (
        f"documented: a producer heartbeat time > 0 sets the guard time to 0; {guard_time:04X}h still reads "
        f"{observed} ms after {producer:04X}h = {period} ms"
    )


def test_guard_time_refused_while_heartbeat_producer(dut, exclusion, settings_journal):
    """While the heartbeat producer runs, writing a non-zero guard time is refused and changes nothing."""
    producer, guard_time, code = exclusion
    settings_journal.write(producer, 0, _u16(dut.profile.timing.heartbeat_test_period_ms))
    before = dut.read_uint(guard_time, 0)
    settings_journal.remember(guard_time, 0)
    response = dut.expect_abort(sdo_frames.expedited_download_request(guard_time, 0, _u16(GUARD_TIME_MS)))
    assert_abort(dut, response, {code}, f"guard time {guard_time:04X}h = {GUARD_TIME_MS} ms while producing heartbeats")
    assert dut.read_uint(guard_time, 0) == before, f"{guard_time:04X}h changed although the write was refused"
