"""TPDO timing measured: the event timer's period, SYNC-to-TPDO latency and the inhibit time (CiA 301 §7.2.2.2,
§7.5.2.37).

Each test takes >= 50 samples from the frame log and records them as a timing measurement (statistics and
a plot in the report, the figures in JUnit), saying which clock stamped the frames. The tester's host is
watched while it measures (LatencyProbe): a figure that fails only where the host itself ran that late
is inconclusive, not the device's. No test starts with an error active or leaves one (fixture no_error_left); the
inhibit time is written with the TPDO not valid (CiA 301 v4.2.0 §7.5.2.37 lets a device require it).
"""

from __future__ import annotations

import itertools
import time

import can
import pytest

from encoder_conformance.cia.cia301 import SYNC_COB_ID
from encoder_conformance.coverage import Hold
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.link import LatencyProbe, format_frames
from encoder_conformance.dut.tpdo import NoUsableTpdo, TpdoUnderTest
from encoder_conformance.plugin.skips import not_applicable, not_equipped, not_judged
from encoder_conformance.plugin.suite_helpers import inconclusive_if_host_late, judge_stream, tpdo_under_test

pytestmark = [pytest.mark.spec("CiA 301 §7.2.2.2 (PDO transmission), §7.5.2.37"), pytest.mark.requires("tpdos"),
              pytest.mark.usefixtures("no_error_left")]

INHIBIT_CLAUSE = "CiA 301 §7.5.2.37 (inhibit time: types 254/255 only; a transmission inside it is delayed, not lost)"
SYNCS = 50
SYNC_SPACING_S = 0.01  # a usual bus cycle; how late the tester sends a SYNC does not matter (both ends are logged)
INHIBIT_MS = 20  # 18xxh sub 3 = 200 x 100 us: 50 intervals in about 1 s
HOLD_INHIBIT_MS = 50  # the delayed-not-lost check: room for the tester to turn the shaft inside the inhibit time
STEP_REV = 0.01  # one shaft step: many position units at any resolution
POSITION = 0x6004  # CiA 406 position value


def test_event_timer_period_within_tolerance(dut, periodic_capture, evidence):
    """Transmission type 255 with event timer T: the TPDO comes every T ms (>= 50 intervals, profile tolerance)."""
    judge_stream(periodic_capture, periodic_capture.event_timer, evidence, dut.profile.timing.heartbeat_tolerance)


def test_sync_to_tpdo_latency(dut, settings_journal, back_to_preoperational, twin_lateness, evidence):
    """Transmission type 1: each of 50 SYNCs, 10 ms apart, is answered by one TPDO (CiA 301), within the profile's
    pdo_response_max_ms of the SYNC (inferred: CiA 301 gives no bound). Latency: the TPDO's timestamp minus its
    SYNC's, both from the frame log."""
    tpdo = tpdo_under_test(dut, 2, evidence, settings_journal, [1])
    comm, cob_id = tpdo.comm, tpdo.can_id()
    tpdo.configure(trans_type=1)
    limit = dut.profile.timing.pdo_response_max_ms

    is_tpdo = tpdo.frames(cob_id)

    started = dut.nmt.command("start")
    dut.send_sync()  # the device is operational once it answers a SYNC (no fixed settle time)
    ready = dut.frames.wait_for(is_tpdo, dut.profile.timing.nmt_settle_ms / 1000 + tpdo.answer_s, started)
    assert ready is not None, f"no TPDO on {cob_id:03X}h ({comm:04X}h type 1) after NMT start and a SYNC"
    mark = dut.frames.mark()
    with LatencyProbe(twin_lateness) as probe:
        for _ in range(SYNCS):
            dut.send_sync()
            dut.frames.quiet_period(lambda m: False, SYNC_SPACING_S)  # the bus cycle: an observation window
        # a late device is judged on its latency, not as missing: wait (returns once all are in)
        tpdos = dut.frames.wait_count(is_tpdo, SYNCS, max(0.5, 5 * limit / 1000), mark)
    host = probe.result()
    syncs = dut.frames.since(mark, lambda m: not m.is_rx and m.arbitration_id == SYNC_COB_ID)
    evidence.measure(f"TPDOs on {cob_id:03X}h for {len(syncs)} SYNCs", len(tpdos), "frames", len(syncs), len(syncs))
    assert len(tpdos) == len(syncs), (
        f"{comm:04X}h.02 = 1: expected one TPDO per SYNC, {len(tpdos)} for {len(syncs)} SYNCs\n"
        f"{format_frames(dut.frames.since(mark)[-12:])}")
    latencies = [(t.timestamp - s.timestamp) * 1000 for s, t in zip(syncs, tpdos, strict=True)]
    clock = dut.frames.clock
    evidence.timing(f"SYNC to TPDO {cob_id:03X}h latency", latencies, nominal_ms=0, low_ms=0, high_ms=limit,
                    clock=clock.describe(own_frames_too=True), sample_label="SYNC",
                    basis=f"inferred: profile timing.pdo_response_max_ms = {limit:g} ms (CiA 301 gives no bound)",
                    judged="every latency within the band (the k-th TPDO answers the k-th SYNC)")
    evidence.note(f"tester host during the capture: {host.describe()}")
    if clock.hardware and min(latencies) < 0:
        not_judged(Hold.CLOCKS_APART, "the SYNCs carry the host's clock and the TPDOs the adapter's, and the two "
                    f"disagree (a TPDO {-min(latencies):.1f} ms before its SYNC); latency needs one clock")
    early = [(n, ms) for n, ms in enumerate(latencies) if ms < 0]
    assert not early, "TPDOs before the SYNC they answer (an unprompted TPDO shifts the pairing): " + ", ".join(
        f"#{n}: {ms:.1f} ms" for n, ms in early[:8])
    late = [(n, ms) for n, ms in enumerate(latencies) if ms > limit]
    if late:
        inconclusive_if_host_late([syncs[n].timestamp for n, _ in late], [ms - limit for _, ms in late], host,
                                   f"SYNC-to-TPDO latency (limit {limit:g} ms)")
        evidence.inferred_problem(
            f"{len(late)} of {len(latencies)} TPDOs later than {limit:g} ms after their SYNC: "
            + ", ".join(f"#{n}: {ms:.1f} ms" for n, ms in late[:8]),
            "profile timing.pdo_response_max_ms (CiA 301 gives no SYNC-to-TPDO bound)")


def _inhibited_tpdo(dut, settings_journal, tpdo_while_invalid, evidence, shaft,
                    inhibit_ms: int) -> tuple[TpdoUnderTest, int]:
    """A change-driven TPDO (254/255, event timer 0) with inhibit time ``inhibit_ms``, and its COB-ID; skips
    where the profile has no such TPDO or the bench cannot turn the shaft."""
    evidence.rests_on("cia", INHIBIT_CLAUSE)
    tpdo = tpdo_under_test(dut, 3, evidence, settings_journal, [254, 255])
    comm, kind = tpdo.comm, tpdo.trans_type
    if shaft is None:
        not_equipped("no shaft drive (--shaft-drive) to change the position inside the inhibit time")
    if not dut.profile.capabilities.encoder or not tpdo.maps_position():
        not_applicable(f"{comm:04X}h maps no position value a turning shaft could change (the changes "
                    "inside the inhibit time come from the shaft)")
    cob_id = tpdo.can_id()
    timer = dut.profile.entry(comm, 5)
    tpdo.configure(trans_type=kind, event_timer=0 if timer is not None and timer.writable else None)
    if timer is not None and not timer.writable and dut.read_uint(comm, 5):
        raise NoUsableTpdo(f"not applicable: {comm:04X}h.05 (event timer) is read-only and not 0", [])
    tpdo.configure_while_invalid(tpdo_while_invalid, inhibit_time=inhibit_ms * 10)
    evidence.note(f"{comm:04X}h: type {kind}, event timer 0, inhibit time {inhibit_ms} ms "
                  f"(sub 3 = {inhibit_ms * 10} x 100 us); TPDO on {cob_id:03X}h")
    return tpdo, cob_id


def test_inhibit_time_spaces_tpdos(dut, settings_journal, tpdo_while_invalid, back_to_preoperational, shaft,
                                   twin_lateness, evidence):
    """A change-driven TPDO with inhibit time 20 ms, the position changed right after each frame (inside every
    inhibit time): no two frames closer than 20 ms (>= 50 intervals; tolerance for the tester's clock)."""
    tpdo, cob_id = _inhibited_tpdo(dut, settings_journal, tpdo_while_invalid, evidence, shaft, INHIBIT_MS)
    comm = tpdo.comm
    tolerance = dut.profile.timing.heartbeat_tolerance.allowed_ms(INHIBIT_MS)

    is_tpdo = tpdo.frames(cob_id)

    mark = dut.nmt.command("start")
    frames: list[can.Message] = []
    reactions: list[float] = []  # ms from a frame to the tester's next position change (inside the inhibit time?)
    # until the first TPDO a change may come before operational and send nothing: looked for the inhibit time, what
    # the device owes and the tester's part, then changed again; after it each change owes a TPDO (the inhibit time
    # plus the PDO answer window, the wait ending when it comes)
    look = (INHIBIT_MS + dut.profile.timing.pdo_response_max_ms) / 1000 + tpdo.silence_s
    wait = INHIBIT_MS / 1000 + tpdo.answer_s
    deadline = Deadline((SYNCS + 1) * 2 * look + dut.profile.timing.nmt_settle_ms / 1000 + tpdo.answer_s)
    with LatencyProbe(twin_lateness) as probe:
        while len(frames) < SYNCS + 1 and not deadline.expired():
            after = dut.frames.mark()
            shaft.turn_by(STEP_REV)
            if frames:
                reactions.append((time.time() - frames[-1].timestamp) * 1000)
            frame = dut.frames.wait_for(is_tpdo, wait if frames else look, after)
            if frame is not None:
                frames = dut.frames.since(mark, is_tpdo)
    host = probe.result()
    spacing = [(b.timestamp - a.timestamp) * 1000 for a, b in itertools.pairwise(frames)]
    clock = dut.frames.clock.describe()
    evidence.timing(f"TPDO {cob_id:03X}h spacing, inhibit time {INHIBIT_MS} ms", spacing, nominal_ms=INHIBIT_MS,
                    low_ms=INHIBIT_MS - tolerance, high_ms=None, clock=clock,
                    basis=f"cia: {INHIBIT_CLAUSE}; tolerance for the tester's clock {tolerance:g} ms "
                          "(profile timing.heartbeat_tolerance)",
                    judged="every interval at least the band's low limit")
    inside = sum(1 for ms in reactions if ms < INHIBIT_MS)
    evidence.note(f"the position changed inside the inhibit time after {inside} of {len(reactions)} frames "
                  f"(tester reaction p50 {sorted(reactions)[len(reactions) // 2]:.1f} ms)" if reactions else
                  "no position change followed a frame")
    evidence.note(f"tester host during the capture: {host.describe()}")
    assert len(spacing) >= SYNCS, (
        f"only {len(frames)} TPDOs on {cob_id:03X}h while the position changed after each (wanted {SYNCS + 1}): "
        f"a change-driven TPDO must follow each change")
    close = [(n, ms) for n, ms in enumerate(spacing) if ms < INHIBIT_MS - tolerance]
    if close:
        inconclusive_if_host_late([frames[n + 1].timestamp for n, _ in close],
                                   [INHIBIT_MS - ms - tolerance for _, ms in close], host,
                                   f"the spacing of TPDO {cob_id:03X}h")
    assert not close, (
        f"{comm:04X}h inhibit time {INHIBIT_MS} ms: {len(close)} of {len(spacing)} frames closer than "
        f"{INHIBIT_MS - tolerance:g} ms to the previous one: "
        + ", ".join(f"#{n + 1}: {ms:.1f} ms" for n, ms in close[:8]))


def test_inhibit_time_delays_events_not_drops(dut, settings_journal, tpdo_while_invalid, back_to_preoperational,
                                              shaft, evidence):
    """A position change inside the inhibit time (50 ms) of a change-driven TPDO is sent when the time is over,
    not dropped: after the shaft stops, the last TPDO carries the position 6004h reads, within inhibit time +
    pdo_response_max_ms of the previous frame."""
    tpdo, cob_id = _inhibited_tpdo(dut, settings_journal, tpdo_while_invalid, evidence, shaft, HOLD_INHIBIT_MS)
    comm = tpdo.comm
    where = tpdo.mapped_bytes_of(POSITION)
    if where is None:
        not_applicable(f"{comm:04X}h does not map the position value {POSITION:04X}h on byte bounds")
    # the inhibit time plus what the device owes plus the tester's part: one look for a change's TPDO, looked again
    # (a change before operational sends nothing) and the delay's bound in the evidence; a TPDO that must come is
    # waited for the inhibit time plus the PDO answer window
    window = (HOLD_INHIBIT_MS + dut.profile.timing.pdo_response_max_ms) / 1000 + tpdo.silence_s
    owed = HOLD_INHIBIT_MS / 1000 + tpdo.answer_s

    is_tpdo = tpdo.frames(cob_id)

    dut.nmt.command("start")
    judged = 0
    for _ in range(3):
        mark = dut.frames.mark()
        first = _tpdo_on_change(dut, shaft, is_tpdo, window, dut.profile.timing.nmt_settle_ms / 1000 + owed)
        assert first is not None, f"no TPDO on {cob_id:03X}h after the position changed"
        following = dut.frames.mark()
        shaft.turn_by(STEP_REV)  # inside the inhibit time the first frame started
        changed_after_ms = (time.time() - first.timestamp) * 1000
        if changed_after_ms >= HOLD_INHIBIT_MS / 2:  # the tester was too slow: this change is no test; its TPDO
            dut.frames.wait_for(is_tpdo, owed, following)  # passes before the next change
            continue
        judged += 1
        delayed = dut.frames.wait_for(is_tpdo, owed, following)
        position = bytes(dut.read(POSITION)[: where.stop - where.start])
        assert delayed is not None, (
            f"{comm:04X}h inhibit time {HOLD_INHIBIT_MS} ms: the position changed {changed_after_ms:.1f} ms after "
            f"a TPDO and no TPDO followed within {owed * 1000:.0f} ms: the change was lost (6004h reads "
            f"{position.hex(' ').upper()}, the last TPDO carried {bytes(first.data[where]).hex(' ').upper()})")
        gap = (delayed.timestamp - first.timestamp) * 1000
        evidence.measure("delay of the change made inside the inhibit time", round(gap, 2), "ms", None,
                         round(window * 1000, 1))
        last = dut.frames.since(mark, is_tpdo)[-1]
        assert bytes(last.data[where]) == position, (
            f"the last TPDO on {cob_id:03X}h carries {bytes(last.data[where]).hex(' ').upper()}, 6004h reads "
            f"{position.hex(' ').upper()}: the change inside the inhibit time was not sent\n"
            f"{format_frames(dut.frames.since(mark, is_tpdo))}")
    if not judged:
        not_judged(Hold.STIMULUS_LATE, f"the tester never changed the position within {HOLD_INHIBIT_MS / 2:g} ms of a "
                    "TPDO (host too slow)")


def _tpdo_on_change(dut, shaft, is_tpdo, window: float, timeout: float) -> can.Message | None:
    """Turn the shaft a step and wait ``window`` for the TPDO, again until ``timeout``: a change the device made
    before it entered operational (the NMT command and the shaft take different paths) sends nothing."""
    deadline = Deadline(timeout)
    while True:
        mark = dut.frames.mark()
        shaft.turn_by(STEP_REV)
        frame = dut.frames.wait_for(is_tpdo, window, mark)
        if frame is not None or deadline.expired():
            return frame
