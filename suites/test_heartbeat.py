"""Heartbeat producer: 1017h sets the period, 0 disables it (CiA 301 §7.2.8.3.2.2, §7.5.2.32)."""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import HEARTBEAT_BASE
from encoder_conformance.dut.link import format_frames
from encoder_conformance.plugin.suite_helpers import judge_stream

pytestmark = [
    pytest.mark.spec("CiA 301 §7.2.8.3.2.2 (heartbeat protocol)"),
    pytest.mark.requires("heartbeat_producer"),
]


def test_heartbeat_period_within_tolerance(dut, periodic_capture, evidence):
    """Over at least 50 intervals, the heartbeat keeps the 1017h period and schedule within the profile's tolerance."""
    judge_stream(periodic_capture, periodic_capture.heartbeat, evidence, dut.profile.timing.heartbeat_tolerance)


def test_heartbeat_frame_format(dut, heartbeat, settings_journal, evidence):
    """Heartbeat frames are 700h+node-id, DLC 1, and report pre-operational as 7Fh."""
    dut.nmt.transition("pre-operational", settings_journal, evidence)  # seen there first (a device may start itself)
    mark = dut.frames.mark()
    samples = dut.heartbeats(mark, 3, timeout=4 * heartbeat / 1000 + 0.5)
    assert len(samples) == 3, f"only {len(samples)} heartbeats within {4 * heartbeat} ms"
    wrong = [s for s in samples if s.dlc != 1 or s.state != 0x7F]
    assert not wrong, "heartbeat in pre-operational must be DLC 1 with 7Fh; observed " + ", ".join(
        f"DLC {s.dlc} state {s.state:02X}h" for s in wrong
    )


def test_heartbeat_zero_disables(dut, heartbeat, settings_journal, evidence):
    """Writing 0 to 1017h stops the heartbeat."""
    mark = dut.frames.mark()
    assert dut.heartbeats(mark, 2, timeout=3 * heartbeat / 1000 + 0.5), "heartbeat did not start"
    settings_journal.write(0x1017, 0, b"\x00\x00")
    stopped = dut.frames.mark()
    # one heartbeat may be in flight when the write is processed; a producer that keeps running sends
    # at least two in two periods (plus the tester's margin)
    window = 2 * heartbeat / 1000 + dut.sdo_silence_s
    heartbeat_id = HEARTBEAT_BASE + dut.node_id
    late = dut.frames.quiet_period(lambda m: m.is_rx and m.arbitration_id == heartbeat_id, window, stopped)
    # one heartbeat may already be on its way when the write is processed
    evidence.measure("heartbeats after 1017h = 0", len(late), "frames", 0, 1)
    assert len(late) <= 1, (
        f"{len(late)} heartbeats in {window * 1000:.0f} ms after 1017h = 0:\n{format_frames(late[:5])}"
    )
