"""TPDO transmission: every n-th SYNC, the event timer in and out of operational (CiA 301 §7.2.2.2, §7.5.2.37);
the timing itself (event-timer period, SYNC latency, inhibit time) is in test_pdo_timing.

Each test configures one TPDO through its communication parameter (put back afterwards), starts the device and
checks it got there (the heartbeat's state byte 05h), and counts or times that TPDO's frames. SYNCs are spaced by
what the device owes: each waits for the TPDO it brings, or the profile's timing.pdo_response_max_ms (SYNC to TPDO)
where none is due. No test starts with an error active or leaves one (fixture no_error_left).
"""

from __future__ import annotations

import pytest

from encoder_conformance.dut.link import NO_PDO_OUTSIDE_OPERATIONAL, format_frames
from encoder_conformance.dut.tpdo import pdo_stimulus
from encoder_conformance.plugin.suite_helpers import documented_quirk, tpdo_under_test
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("CiA 301 §7.2.2.2 (PDO transmission), §7.5.2.37"), pytest.mark.requires("tpdos"),
              pytest.mark.usefixtures("no_error_left")]


def test_sync_tpdo_sent_on_every_nth_sync(dut, settings_journal, back_to_preoperational, evidence):
    """Transmission type 3: the TPDO follows every third SYNC, so 9 SYNCs give exactly 3 frames."""
    tpdo = tpdo_under_test(dut, 2, evidence, settings_journal, [3, *range(2, 241), 1])
    comm, every = tpdo.comm, tpdo.trans_type
    cob_id = tpdo.can_id()
    tpdo.configure(trans_type=every)
    dut.nmt.transition("operational", settings_journal, evidence)
    mark = dut.frames.mark()
    syncs = 3 * every
    owed = dut.profile.timing.pdo_response_max_ms / 1000
    for _ in range(syncs):  # each SYNC processed before the next: its TPDO came, or the time the device owes passed
        dut.frames.wait_for(tpdo.frames(cob_id), owed, dut.send_sync())
    evidence.note(f"{syncs} SYNCs, each after the TPDO the previous one brought or timing.pdo_response_max_ms "
                  f"({owed * 1000:g} ms, SYNC to TPDO)")
    window = dut.sdo_timeout + dut.profile.timing.nmt_settle_ms / 1000
    pdos = dut.pdos_counted(tpdo.frames(cob_id), 3, mark, window)
    evidence.measure(f"TPDO {cob_id:03X}h frames for {syncs} SYNCs", len(pdos), "frames", 3, 3)
    assert len(pdos) == 3, (
        f"{comm:04X}h.02 = {every}: expected 3 TPDOs on {cob_id:03X}h for {syncs} SYNCs, observed {len(pdos)}\n"
        f"{format_frames(dut.frames.since(mark)[:20])}"
    )


def test_type_255_without_event_timer_sends_nothing(dut, settings_journal, back_to_preoperational, shaft, evidence):
    """Documented quirk: transmission type 255 with event timer 0 switches the TPDO off (no SYNC, no change)."""
    documented_quirk(dut, fx.TransmissionType255Timer0Disables, evidence,
                     "CiA 301 type 255 without timer is event-driven")
    tpdo = tpdo_under_test(dut, 5, evidence, settings_journal, [255])
    comm, cob_id = tpdo.comm, tpdo.can_id()
    tpdo.configure(trans_type=255, event_timer=0)
    dut.nmt.transition("operational", settings_journal, evidence)
    control = shaft
    if control is None:
        evidence.note("hardware: only SYNCs are sent; turn the shaft during the test to cover position changes")
    mark = pdo_stimulus(dut, control)
    pdos = dut.frames.since(mark, tpdo.frames(cob_id))
    evidence.measure(f"TPDO {cob_id:03X}h frames with type 255, timer 0", len(pdos), "frames", 0, 0)
    assert not pdos, (
        f"{comm:04X}h.02 = 255 and sub 5 = 0 must switch the TPDO off (documented); observed {len(pdos)} on "
        f"{cob_id:03X}h during 10 SYNCs{' and a turning shaft' if control else ''}:\n{format_frames(pdos[:5])}"
    )


@pytest.mark.parametrize("state", ["pre-operational", "stop"], ids=["pre-operational", "stopped"])
def test_event_timer_tpdo_stops_when_leaving_operational(dut, settings_journal, back_to_preoperational, evidence,
                                                        state):
    """A TPDO whose event timer is running when the device leaves operational sends nothing more in pre-operational
    or stopped (CiA 301 §7.3.2.2: PDOs only in operational), and sends again after NMT start."""
    evidence.rests_on("cia", NO_PDO_OUTSIDE_OPERATIONAL)
    tpdo = tpdo_under_test(dut, 5, evidence, settings_journal, [255, 254])
    comm, cob_id = tpdo.comm, tpdo.can_id()
    period_s = 0.02
    tpdo.configure(trans_type=tpdo.trans_type, event_timer=round(period_s * 1000))

    is_this_tpdo = tpdo.frames(cob_id)

    # TPDOs that must come: the timer's periods plus the PDO answer window (the waits end when they came); a TPDO
    # that must not come: the same periods plus the PDO silence window
    owed, window = 5 * period_s + tpdo.answer_s, 5 * period_s + tpdo.silence_s
    mark = dut.frames.mark()
    dut.nmt.transition("operational", settings_journal, evidence)
    running = dut.frames.wait_count(is_this_tpdo, 2, owed, mark)
    assert len(running) == 2, f"{comm:04X}h with event timer {period_s * 1000:.0f} ms: {len(running)} TPDO(s) in " \
                              f"operational within {owed * 1000:.0f} ms"
    sent = dut.nmt.command(state)
    # a TPDO after the heartbeat shows the state is this state's, also after the window (dut/link/late_frames.py)
    dut.frames.late.open_state(dut.node_id, state, is_this_tpdo, f"TPDO {cob_id:03X}h",
                               NO_PDO_OUTSIDE_OPERATIONAL)
    dut.nmt.settle(sent, state)  # the state change: until the heartbeat reports it, at most the settle time
    after = dut.frames.mark()
    late = dut.frames.quiet_period(is_this_tpdo, window, after)
    evidence.measure(f"TPDO {cob_id:03X}h frames in {state} (event timer running at the transition)", len(late),
                     "frames", 0, 0)
    assert not late, f"{len(late)} TPDO(s) on {cob_id:03X}h in {state}, {window * 1000:.0f} ms after the " \
                     f"transition (event timer {period_s * 1000:.0f} ms):\n{format_frames(late[:5])}"
    again = dut.frames.mark()
    dut.nmt.transition("operational", settings_journal, evidence)
    resumed = dut.frames.wait_for(is_this_tpdo, owed, again)
    assert resumed is not None, f"no TPDO on {cob_id:03X}h within {owed * 1000:.0f} ms after NMT start again"
