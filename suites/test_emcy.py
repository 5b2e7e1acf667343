"""EMCY producer (CiA 301 §7.2.7): frame layout, COB-ID and its valid bit (1014h), inhibit time (1015h), error
register bit 0 (1001h), the error-reset EMCY, the NMT states that allow EMCY, and the triggers an encoder without
RPDOs offers (a SYNC of the wrong length, a heartbeat-consumer time-out). The error history 1003h:
test_emcy_history.py.

Errors come from a trigger the bench and the device offer (plugin/suite_helpers/emcy.py: the bench's error stimulus,
else the bus triggers). A bench run adds entries to the device's error history (1003h) with each error; clearing them
needs the clear (1003h sub 0 = 0), which only test_emcy_history's clearing test sends. Settings the tests change (1014h,
1015h, 1019h, 1016h) are put back afterwards (on a SIKO each write of 1014h is stored by the device itself); an error
still active after a test (a bus trigger's) is cleared by NMT reset communication (fixtures/emcy.py), so that no
later test inherits it (a device may hold a communication error out of operational).
"""

from __future__ import annotations

import itertools

import can
import pytest

from encoder_conformance.cia.cia301 import (
    COB_ID_INVALID,
    EMCY_COB_ID,
    EMCY_INHIBIT_TIME,
    ERROR_REGISTER,
    ERROR_REGISTER_GENERIC,
    HEARTBEAT_BASE,
    EmcyCode,
)
from encoder_conformance.coverage import Hold
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.emcy import HeartbeatTimeout, SyncLengthError, emcy_code, is_any_emcy
from encoder_conformance.dut.link import LatencyProbe, format_frames
from encoder_conformance.dut.nmt import raise_if_held_by_error
from encoder_conformance.plugin.skips import not_applicable, not_judged
from encoder_conformance.plugin.suite_helpers import inconclusive_if_host_late
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("CiA 301 §7.2.7 (EMCY)"), pytest.mark.requires("emcy")]

STATE_CLAUSE = "CiA 301 §7.3.2.2 (EMCY in pre-operational and operational, not in stopped)"
INHIBIT_MS = 20  # 1015h = 200 x 100 us
INHIBIT_SAMPLES = 20  # intervals measured (each error adds an entry to a real device's 1003h)


def _writable(dut, index: int, what: str) -> None:
    entry = dut.profile.entry(index, 0)
    if entry is None or not entry.writable:
        not_applicable(f"the profile has no writable {index:04X}h ({what})")


def test_emcy_frame_on_error(dut, emcy, evidence):
    """An error produces one 8-byte EMCY on the 1014h COB-ID (080h + node-ID without 1014h) with its code and the
    error register 1001h in byte 2."""
    evidence.rests_on("cia", "CiA 301 §7.2.7 (EMCY: error code, 1001h, 5 manufacturer bytes; COB-ID 1014h)")
    trigger = emcy.trigger()
    frame = emcy.wait(trigger.fire(), trigger, f"after {trigger.name}")
    assert frame.dlc == 8, f"EMCY has DLC {frame.dlc}, CiA 301 requires 8"
    register = dut.read_uint(ERROR_REGISTER)
    assert frame.data[2] == register, f"EMCY byte 2 = {frame.data[2]:02X}h but 1001h = {register:02X}h"


def test_error_register_generic_bit(dut, emcy, evidence):
    """While an error is present, the error register (EMCY byte 2 and 1001h) has bit 0 (generic error) set with
    any other bit."""
    evidence.rests_on("cia", "CiA 301 §7.5.2 object 1001h (bit 0 generic error: set whenever an error is present)")
    found = dut.profile.quirk(fx.ErrorRegisterWithoutGenericBit)
    if found is not None:
        evidence.deviation(found.id, found.quirk.title)
        not_applicable(f"quirk {found.id} documents 1001h without bit 0 (deviation recorded)")
    trigger = emcy.trigger()
    frame = emcy.wait(trigger.fire(), trigger, f"after {trigger.name}")
    register = dut.read_uint(ERROR_REGISTER)
    evidence.note(f"EMCY byte 2 = {frame.data[2]:02X}h, 1001h = {register:02X}h")
    assert frame.data[2] & ERROR_REGISTER_GENERIC, (
        f"EMCY {emcy_code(frame):04X}h carries error register {frame.data[2]:02X}h without bit 0 (generic error)")
    assert not register or register & ERROR_REGISTER_GENERIC, f"1001h = {register:02X}h without bit 0"


def test_emcy_cob_id_valid_bit(dut, emcy, settings_journal, evidence):
    """With 1014h bit 31 set (EMCY not valid) an error sends no EMCY, on any EMCY CAN-ID; with it clear again the
    next error does."""
    evidence.rests_on("cia", "CiA 301 §7.5.2 object 1014h (bit 31 = 1: EMCY does not exist / is not valid)")
    _writable(dut, EMCY_COB_ID, "COB-ID EMCY")
    trigger = emcy.trigger()
    found = dut.read_uint(EMCY_COB_ID)
    valid = found & ~COB_ID_INVALID
    settings_journal.write(EMCY_COB_ID, 0, (valid | COB_ID_INVALID).to_bytes(4, "little"))
    mark = trigger.fire()
    sent = dut.frames.quiet_period(is_any_emcy, trigger.silence_s(), mark)
    assert not sent, (f"1014h = {valid | COB_ID_INVALID:08X}h (not valid): EMCY sent after {trigger.name}\n"
                      f"{format_frames(sent)}")
    dut.write(EMCY_COB_ID, 0, valid.to_bytes(4, "little"))
    emcy.wait(trigger.fire(), trigger, f"1014h = {valid:08X}h (valid again), after {trigger.name}")


def test_emcy_inhibit_time_spaces_emcys(dut, emcy, settings_journal, back_to_preoperational, twin_lateness,
                                        evidence):
    """1015h = 20 ms, a new error (or the error going away) right after each EMCY: no two EMCYs closer than 20 ms
    (>= 20 intervals; a tolerance for the tester's clock). A device that drops the events inside the inhibit time
    passes too; one that sends too few EMCYs to measure is not judged (events left unanswered after the inhibit time,
    each kind of event once, end the capture: even a device that drops events owed an EMCY for them)."""
    evidence.rests_on("cia", "CiA 301 §7.5.2 object 1015h (inhibit time EMCY, 100 us units)")
    _writable(dut, EMCY_INHIBIT_TIME, "inhibit time EMCY")
    trigger = emcy.trigger(repeatable=True)
    settings_journal.write(EMCY_INHIBIT_TIME, 0, (INHIBIT_MS * 10).to_bytes(2, "little"))
    tolerance = dut.profile.timing.heartbeat_tolerance.allowed_ms(INHIBIT_MS)
    cob_id = emcy.cob_id()
    mark = dut.frames.mark()
    frames: list[can.Message] = []
    actions = itertools.cycle([trigger.fire, trigger.clear] if trigger.clears else [trigger.fire])
    deadline = Deadline((INHIBIT_SAMPLES + 1) * 2 * (INHIBIT_MS / 1000 + trigger.answer_s()))
    # events in a row without an EMCY that end the capture: one more than the cycle has steps, so that every kind
    # of event came once after the inhibit time (a device that dropped the clear inside it may ignore the next
    # fire, its error still active, but owes the error reset EMCY for the clear after that)
    give_up_after = 3 if trigger.clears else 2
    unanswered = 0
    with LatencyProbe(twin_lateness) as probe:
        while len(frames) < INHIBIT_SAMPLES + 1 and not deadline.expired() and unanswered < give_up_after:
            after = next(actions)()
            if dut.frames.wait_for(cob_id.matches, INHIBIT_MS / 1000 + trigger.answer_s(), after) is None:
                unanswered += 1
                continue
            unanswered = 0
            frames = dut.frames.since(mark, cob_id.matches)
    host = probe.result()
    spacing = [(b.timestamp - a.timestamp) * 1000 for a, b in itertools.pairwise(frames)]
    evidence.timing(f"EMCY {cob_id.can_id or 0:03X}h spacing, inhibit time {INHIBIT_MS} ms", spacing,
                    nominal_ms=INHIBIT_MS, low_ms=INHIBIT_MS - tolerance, high_ms=None,
                    clock=dut.frames.clock.describe(),
                    basis=f"cia: CiA 301 §7.5.2 object 1015h; tolerance for the tester's clock {tolerance:g} ms "
                          "(profile timing.heartbeat_tolerance)",
                    judged="every interval at least the band's low limit")
    evidence.note(f"tester host during the capture: {host.describe()}")
    if len(spacing) < INHIBIT_SAMPLES:
        not_judged(Hold.EMCY_NOT_REPEATED, f"{len(frames)} EMCYs for {trigger.name} repeated (wanted "
                    f"{INHIBIT_SAMPLES + 1}); the device signals a repeated error less often")
    close = [(n, ms) for n, ms in enumerate(spacing) if ms < INHIBIT_MS - tolerance]
    if close:
        inconclusive_if_host_late([frames[n + 1].timestamp for n, _ in close],
                                  [INHIBIT_MS - ms - tolerance for _, ms in close], host, "the EMCY spacing")
    assert not close, (
        f"1015h = {INHIBIT_MS} ms: {len(close)} of {len(spacing)} EMCYs closer than {INHIBIT_MS - tolerance:g} ms "
        "to the previous one: " + ", ".join(f"#{n + 1}: {ms:.1f} ms" for n, ms in close[:8]))


def test_error_reset_emcy_when_cause_goes_away(dut, emcy, evidence):
    """When the cause of the error goes away the device sends the EMCY 0000h (error reset) and the error register
    loses bit 0."""
    evidence.rests_on("cia", "CiA 301 §7.2.7 (EMCY 0000h: error reset or no error)")
    trigger = emcy.trigger(clears=True)
    raise_if_held_by_error(dut, "the error reset", "so bit 0 stays set whatever the test's error does")
    emcy.wait(trigger.fire(), trigger, f"after {trigger.name}")
    frame = emcy.wait(trigger.clear(), trigger, "after the cause went away", code=EmcyCode.ERROR_RESET)
    register = dut.read_uint(ERROR_REGISTER)
    evidence.note(f"error reset EMCY byte 2 = {frame.data[2]:02X}h, 1001h = {register:02X}h")
    assert not register & ERROR_REGISTER_GENERIC, f"no error left, but 1001h = {register:02X}h (bit 0 set)"


@pytest.mark.parametrize("state", ["pre-operational", "operational"])
def test_emcy_sent_in_state(dut, emcy, settings_journal, back_to_preoperational, evidence, state):
    """An error in pre-operational and in operational (seen in the heartbeat) sends its EMCY."""
    evidence.rests_on("cia", STATE_CLAUSE)
    trigger = emcy.trigger()
    if state == "operational":
        dut.nmt.transition("operational", settings_journal, evidence)
    emcy.wait(trigger.fire(), trigger, f"in {state}, after {trigger.name}")


def test_no_emcy_in_stopped(dut, emcy, settings_journal, back_to_preoperational, evidence):
    """An error in stopped sends no EMCY (only NMT and error control work there); where the manual lists EMCY in
    stopped (quirk), whether one came is recorded."""
    evidence.rests_on("cia", STATE_CLAUSE)
    trigger = emcy.trigger()
    cob_id = emcy.cob_id()
    dut.nmt.transition("stopped", settings_journal, evidence)  # seen there (heartbeat 04h) before the error is caused
    mark = trigger.fire()
    sent = dut.frames.quiet_period(cob_id.matches, trigger.silence_s(), mark)
    found = dut.profile.quirk(fx.EmcyInStopped)
    dut.nmt.back_to_preoperational()
    if found is not None:
        evidence.deviation(found.id, found.quirk.title)
        evidence.note(f"in stopped, after {trigger.name}: " + ("EMCY sent" if sent else "no EMCY"))
        return
    assert not sent, f"EMCY in stopped after {trigger.name}\n{format_frames(sent)}"


def _bus_trigger(kind, dut, settings_journal, evidence):
    """A trigger the tester fires on the bus, with what its verdict rests on; skips where the device lacks it."""
    why = kind.available(dut)
    if why is not None:
        not_applicable(f"{why}")
    trigger = kind(dut, settings_journal.write)
    evidence.rests_on(*trigger.basis)
    return trigger


def test_emcy_on_sync_length(dut, emcy, settings_journal, evidence):
    """With 1019h = 8 (SYNC with counter), a SYNC carrying its counter gives no EMCY 8240h and a SYNC without the
    counter byte gives EMCY 8240h (unexpected SYNC data length): an EMCY trigger without RPDOs."""
    trigger = _bus_trigger(SyncLengthError, dut, settings_journal, evidence)
    cob_id = emcy.cob_id()
    right = dut.send(trigger.sync_cob_id, b"\x01")
    wrong = dut.frames.quiet_period(lambda m: cob_id.matches(m) and emcy_code(m) == trigger.code,
                                    trigger.silence_s(), right)
    assert not wrong, f"EMCY 8240h after a SYNC with counter 1 (1019h = 8)\n{format_frames(wrong)}"
    emcy.wait(trigger.fire(), trigger, f"after {trigger.name}", judged=True)


def test_emcy_on_heartbeat_consumer_timeout(dut, emcy, settings_journal, evidence):
    """1016h.01 watching a node the tester plays: one heartbeat of it, then silence: the time-out's EMCY (8130h, or
    the code the manual gives) comes no sooner than the consumer time after that heartbeat."""
    trigger = _bus_trigger(HeartbeatTimeout, dut, settings_journal, evidence)
    beat = trigger.fire()
    frame = emcy.wait(beat, trigger, f"after {trigger.name}", judged=True)
    sent = dut.frames.since(beat, lambda m: m.arbitration_id == HEARTBEAT_BASE + trigger.producer)
    after_ms = (frame.timestamp - sent[0].timestamp) * 1000 if sent else None
    if after_ms is not None:
        tolerance = dut.profile.timing.heartbeat_tolerance.allowed_ms(trigger.timeout_ms)
        evidence.measure("EMCY after the producer's last heartbeat", round(after_ms, 1), "ms",
                         trigger.timeout_ms - tolerance, None)
        assert after_ms >= trigger.timeout_ms - tolerance, (
            f"time-out EMCY {after_ms:.1f} ms after the heartbeat, the consumer time is {trigger.timeout_ms} ms")
