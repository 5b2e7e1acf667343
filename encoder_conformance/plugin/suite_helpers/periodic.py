"""The verdicts on the periodic capture (``dut/tpdo/periodic_capture.py``): each stream judged by the test that asks
for it, with the capture's notes and documented deviations in its evidence."""

from __future__ import annotations

import pytest

from encoder_conformance.dut.tpdo import PeriodicCapture, PeriodicStream
from encoder_conformance.plugin.evidence import Evidence
from encoder_conformance.plugin.skips import skip_text
from encoder_conformance.plugin.suite_helpers.checks import check_periodic
from encoder_conformance.profile.schema import HeartbeatTolerance


def replay(stream: PeriodicStream, evidence: Evidence) -> None:
    """Into a test's evidence: the capture's notes and documented deviations; skips or fails as captured."""
    for quirk_id, text in stream.deviations:
        evidence.deviation(quirk_id, text)
    for note in stream.notes:
        evidence.note(note)
    if stream.skip:
        skip_text(stream.skip, stream.skip_hold)
    if stream.error:
        pytest.fail(stream.error, pytrace=False)


def judge_stream(capture: PeriodicCapture, stream: PeriodicStream, evidence: Evidence,
                 tolerance: HeartbeatTolerance) -> None:
    """One stream's verdict: all frames in time, on the period and schedule (``check_periodic``)."""
    replay(stream, evidence)
    other = capture.event_timer if stream is capture.heartbeat else capture.heartbeat
    if other.timestamps:
        evidence.note(f"captured together with the {other.what} during {capture.captured_in} (its bus trace)")
    frames = ("heartbeats (1017h" if stream is capture.heartbeat
              else f"TPDOs on {stream.cob_id or 0:03X}h (event timer") + f" = {stream.period_ms} ms)"
    assert len(stream.timestamps) == stream.wanted, (
        f"only {len(stream.timestamps)} of {stream.wanted} {frames} in time"
    )
    check_periodic(stream.timestamps, stream.period_ms, tolerance, stream.what, evidence, capture.host, capture.clock)
