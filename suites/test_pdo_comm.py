"""TPDO communication parameters (CiA 301 §7.5.2.37): COB-ID valid and RTR bits, COB-ID changes, restricted
CAN-IDs, transmission types 0, 252/253 and 254/255, the SYNC start value with the SYNC counter (1019h), writes
in pre-operational only (quirk), and that no trigger sends a TPDO after the device left operational.

Each test configures one TPDO (put back afterwards, also on failure) in pre-operational, starts the device and
checks it got there (the heartbeat's state byte 05h), and watches that TPDO's frames; every pause is an observation
window on the frame log. No test starts with an error active or leaves one (fixture no_error_left: 1001h checked
before and after, NMT reset communication where an error shows, noted in the evidence).
"""

from __future__ import annotations

import contextlib

import can
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import (
    COB_ID_FIXED_WHILE_VALID,
    COB_ID_INVALID,
    COB_ID_NO_RTR,
    COMMUNICATION_CYCLE_PERIOD,
    PDO_MAPPING_OFFSET,
    RESTRICTED_CAN_IDS,
    SYNC_COB_ID,
    SYNC_COUNTER_OVERFLOW,
    SdoAbortCode,
    can_id_of,
    cob_id_valid,
    is_restricted_can_id,
    with_can_id,
)
from encoder_conformance.coverage import Hold
from encoder_conformance.dut.link import NO_PDO_OUTSIDE_OPERATIONAL, answer_window, format_frames, received_on
from encoder_conformance.dut.sdo import abort_name, sdo_frames
from encoder_conformance.dut.tpdo import TpdoUnderTest, fixed_behaviour_tpdos
from encoder_conformance.plugin.skips import not_applicable, not_equipped, not_judged
from encoder_conformance.plugin.suite_helpers import abort_accepted, expected_aborts, tpdo_under_test
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.value_domain import declared_domain

pytestmark = [pytest.mark.spec("CiA 301 §7.5.2.37 (TPDO communication parameter)"), pytest.mark.requires("tpdos"),
              pytest.mark.usefixtures("no_error_left")]

SYNC_TYPES = [1, *range(2, 241)]
EVENT_TYPES = [255, 254]
TURN = 0.05  # revolutions: enough to change any position value
#: the ends of each restricted range, and 001h (CiA 301 §7.3.5): 000h, 001h, 07Fh, 101h, 180h, 581h, ... 7FFh
RESTRICTED_PROBES = sorted({0x001} | {end for span in RESTRICTED_CAN_IDS for end in (span[0], span[-1])})
ANY_ABORT = "CiA 301 names no abort code here: any abort refuses the write"


# -- helpers -------------------------------------------------------------------------------------------
def _u32(value: int) -> bytes:
    return value.to_bytes(4, "little")


def _window(dut) -> float:
    """How long to wait for a TPDO that must come after its trigger (the PDO answer window and the settle time: the
    wait ends when it comes)."""
    return dut.pdo_answer_s + dut.profile.timing.nmt_settle_ms / 1000


def _syncs(dut, count: int, cob_id: int, until_first: bool = False) -> list[can.Message]:
    """``count`` SYNCs, one PDO silence window after each (``until_first``: a TPDO is owed, each SYNC waits up to
    the PDO answer window for it, and the first ends the SYNCs): the TPDOs on ``cob_id`` they brought."""
    mark = dut.frames.mark()
    for _ in range(count):
        dut.send_sync()
        if until_first and dut.frames.wait_for(received_on(cob_id), dut.pdo_answer_s, mark) is not None:
            break
        if not until_first:
            dut.frames.quiet_period(lambda m: False, dut.pdo_silence_s)
    return dut.frames.since(mark, received_on(cob_id))


def _need_shaft(shaft, what: str) -> None:
    if shaft is None:
        not_equipped(f"{what} needs a turning shaft (the twin, or --shaft-drive)")


def _event_tpdo(dut, evidence, settings_journal, shaft) -> TpdoUnderTest:
    """A TPDO of type 254/255 with event timer 0 that maps the position (so a turning shaft is a change of
    its value), set up; skips where the profile has none or a quirk decides its change-driven sending."""
    _need_shaft(shaft, "a change of state")
    if not dut.profile.capabilities.encoder:
        not_applicable("not an encoder; a change of its mapped values is not the bench's to cause")
    found = dut.profile.quirk(fx.TransmissionType255Timer0Disables)
    types = EVENT_TYPES
    if found is not None:
        evidence.deviation(found.id, found.quirk.title)
        types = [254]
    tpdo = tpdo_under_test(dut, 5, evidence, settings_journal, types)
    comm = tpdo.comm
    repeat = dut.profile.quirk(fx.PdoSendRepeatCounters)
    if repeat is not None and comm in repeat.params.per_change:
        evidence.deviation(repeat.id, repeat.quirk.title)
        not_applicable(f"{comm:04X}h's change-driven sending is set by a send-repeat counter "
                    f"(quirk {repeat.id}; test_pdo_repeat checks it)")
    if not tpdo.maps_position():
        not_applicable(f"{comm:04X}h maps no position value the shaft could change")
    tpdo.configure(trans_type=tpdo.trans_type, event_timer=0)
    return tpdo


def _sync_tpdo(dut, evidence, settings_journal, types: list[int] | None = None) -> TpdoUnderTest:
    """A TPDO sent on SYNC (type 1 where it may be written), set up."""
    tpdo = tpdo_under_test(dut, 2, evidence, settings_journal, types or SYNC_TYPES)
    tpdo.configure(trans_type=tpdo.trans_type)
    return tpdo


def _judge_code(dut, response, wanted: set[int], what: str, evidence, rests_on: str) -> None:
    """A refusal is what CiA requires (asserted by the caller); its code only our reading (a warning)."""
    if not abort_accepted(dut, response, wanted):
        evidence.inferred_problem(f"{what}: aborted with {abort_name(response.abort_code or 0)}, expected "
                                  f"{' or '.join(abort_name(c) for c in sorted(wanted))}", rests_on)


def _write_refused(dut, settings_journal, comm: int, sub: int, value: int, what: str) -> sdo_frames.SdoResponse:
    """Raw write that must be refused: the response (asserted to be an abort), the entry put back if not."""
    settings_journal.remember(comm, sub)
    response = dut.expect_abort(sdo_frames.expedited_download_request(comm, sub, _u32(value)))
    if not response.is_abort:
        with contextlib.suppress(SdoAbortedError, AssertionError):  # teardown retries and reports
            _put_back_cob_id(dut, comm, value)
    assert response.is_abort, f"{what}: accepted ({response.describe()}); {ANY_ABORT}"
    return response


def _put_back_cob_id(dut, comm: int, now: int) -> None:
    """After a wrongly accepted COB-ID: invalid first (same bits 0-29), so that the journal may change it."""
    dut.write(comm, 1, _u32(now | COB_ID_INVALID))


def _writable_cob_id(dut, comm: int | None = None, made_valid: bool = False) -> int:
    """A TPDO whose sub 1 is writable and that is not fixed by a layout quirk; skips where there is none.
    ``made_valid``: the test makes it valid, so one that is invalid and maps nothing is passed over (CiA 301
    does not say a device must accept a valid PDO with nothing mapped; CANopenNode refuses it with 06090030h)."""
    fixed, _ = fixed_behaviour_tpdos(dut)
    for index in sorted(i for i in dut.profile.objects if 0x1800 <= i <= 0x19FF and i not in fixed):
        entry = dut.profile.entry(index, 1)
        if entry is None or not entry.writable or (comm is not None and index != comm):
            continue
        if made_valid and dut.read_uint(index, 1) & COB_ID_INVALID and not dut.read_uint(index + PDO_MAPPING_OFFSET, 0):
            continue
        return index
    not_applicable("no TPDO COB-ID (18xxh sub 1) is writable" + (" on a TPDO that is valid or maps something"
                                                                 if made_valid else ""))


# -- COB-ID: valid bit, changes, restricted CAN-IDs -------------------------------------------------------
TIMER_S = 0.02  # the event timer test_invalid_tpdo_sends_nothing sets


@pytest.mark.parametrize("trigger", ["SYNC", "event timer"])
def test_invalid_tpdo_sends_nothing(dut, settings_journal, back_to_preoperational, evidence, trigger):
    """With 18xxh sub 1 bit 31 set the TPDO is not sent on its trigger; with the bit cleared it is sent again."""
    evidence.rests_on("cia", "CiA 301 §7.5.2.37 (COB-ID bit 31: PDO does not exist / is not valid)")
    if trigger == "SYNC":
        tpdo = _sync_tpdo(dut, evidence, settings_journal, [1])
    else:
        tpdo = tpdo_under_test(dut, 5, evidence, settings_journal, EVENT_TYPES)
        tpdo.configure(trans_type=tpdo.trans_type, event_timer=round(TIMER_S * 1000))
    comm = tpdo.comm
    _writable_cob_id(dut, comm)
    cob = tpdo.cob_id()
    cob_id = can_id_of(cob)

    def frames(expected: bool = True) -> list[can.Message]:
        """The TPDOs of three SYNCs or five event-timer periods (up to the first where one is ``expected``)."""
        dut.nmt.transition("operational", settings_journal, evidence)
        if trigger == "SYNC":
            found = _syncs(dut, 3, cob_id, until_first=expected)
        elif expected:  # a TPDO the 20 ms timer owes: the answer window ends when it comes
            found = dut.frames.wait_count(received_on(cob_id), 1, answer_window(TIMER_S), dut.frames.mark())
        else:  # five timer periods of silence
            found = dut.frames.quiet_period(received_on(cob_id), 5 * TIMER_S)
        dut.nmt.back_to_preoperational()
        return found

    assert frames(), f"{comm:04X}h valid ({cob:08X}h): no TPDO on {cob_id:03X}h on its {trigger} in operational"
    settings_journal.write(comm, 1, _u32(cob | COB_ID_INVALID))
    silent = frames(expected=False)
    evidence.measure(f"TPDO {cob_id:03X}h frames with bit 31 set ({trigger})", len(silent), "frames", 0, 0)
    assert not silent, (f"{comm:04X}h.01 = {cob | COB_ID_INVALID:08X}h (not valid): {len(silent)} TPDO(s) on "
                        f"{cob_id:03X}h on its {trigger}:\n{format_frames(silent[:5])}")
    dut.write(comm, 1, _u32(cob))
    assert frames(), f"{comm:04X}h valid again ({cob:08X}h): no TPDO on {cob_id:03X}h on its {trigger}"


def _other_can_id(can_id: int) -> int:
    """A CAN-ID next to ``can_id`` that is not restricted."""
    return next(c for c in (can_id + 1, can_id - 1, can_id + 2, 0x200 + (can_id & 0x7F)) if not is_restricted_can_id(c))


def test_cob_id_change_refused_while_valid(dut, settings_journal, evidence):
    """A write that changes the CAN-ID of a valid TPDO is refused and changes nothing; with bit 31 set first,
    the same change is accepted (then put back)."""
    evidence.rests_on("cia", "CiA 301 §7.5.2.37 (bits 0-29 shall not be changed while the PDO exists)")
    comm = _writable_cob_id(dut, made_valid=True)
    found = dut.read_uint(comm, 1)
    settings_journal.remember(comm, 1, _u32(found))
    if found & COB_ID_INVALID:
        settings_journal.write(comm, 1, _u32(cob_id_valid(found)))
        evidence.note(f"{comm:04X}h.01 bit 31 cleared (TPDO valid) for the test")
    valid = cob_id_valid(found)
    other = _other_can_id(can_id_of(valid))
    moved = with_can_id(valid, other)
    what = f"{comm:04X}h.01 = {moved:08X}h while it reads {valid:08X}h (valid)"
    response = _write_refused(dut, settings_journal, comm, 1, moved, what)
    _judge_code(dut, response, {SdoAbortCode.VALUE_INVALID}, what, evidence,
                "06090030h as CANopenNode answers it; " + ANY_ABORT)
    after = dut.read_uint(comm, 1)
    assert after == valid, f"after the refused {what}: reads {after:08X}h"
    settings_journal.write(comm, 1, _u32(valid | COB_ID_INVALID))
    dut.write(comm, 1, _u32(moved | COB_ID_INVALID))  # not valid: CiA 301 lets bits 0-29 change
    after = dut.read_uint(comm, 1)
    assert after & COB_ID_FIXED_WHILE_VALID == moved & COB_ID_FIXED_WHILE_VALID, (
        f"{comm:04X}h.01 = {moved | COB_ID_INVALID:08X}h (not valid) confirmed, but reads {after:08X}h")


def test_restricted_cob_id_refused(dut, settings_journal, evidence):
    """A valid TPDO COB-ID with a restricted CAN-ID (000h-07Fh, 101h-180h, 581h-5FFh, 601h-67Fh, 6E0h-7FFh) is
    refused, and the entry keeps its value."""
    evidence.rests_on("cia", "CiA 301 §7.3.5 (restricted CAN-IDs)")
    comm = _writable_cob_id(dut)
    found = dut.read_uint(comm, 1)
    invalid = found | COB_ID_INVALID
    settings_journal.write(comm, 1, _u32(invalid))  # not valid: only the restriction may refuse the writes
    rests_on = "06090030h (value range of parameter exceeded) as the CTT expects for 1005h; " + ANY_ABORT
    accepted = []
    for can_id in RESTRICTED_PROBES:
        value = with_can_id(cob_id_valid(found), can_id)
        what = f"{comm:04X}h.01 = {value:08X}h (restricted CAN-ID {can_id:03X}h)"
        response = dut.expect_abort(sdo_frames.expedited_download_request(comm, 1, _u32(value)))
        evidence.note(f"{can_id:03X}h: {response.describe()}")
        if not response.is_abort:
            accepted.append(what)
            _put_back_cob_id(dut, comm, value)
            dut.write(comm, 1, _u32(invalid))
            continue
        _judge_code(dut, response, {SdoAbortCode.VALUE_INVALID}, what, evidence, rests_on)
    evidence.measure("restricted CAN-IDs refused", len(RESTRICTED_PROBES) - len(accepted), "",
                     len(RESTRICTED_PROBES), len(RESTRICTED_PROBES))
    assert not accepted, "accepted: " + "; ".join(accepted)
    assert dut.read_uint(comm, 1) == invalid, f"{comm:04X}h.01 changed by the refused writes"


# -- RTR -------------------------------------------------------------------------------------------------
def _rtr_dlc(dut, comm: int) -> int:
    """The DLC of the TPDO (a remote frame asks for it): from its mapping, or the layout quirk's polled spec."""
    if dut.profile.entry(comm + PDO_MAPPING_OFFSET, 0) is not None:
        count = dut.read_uint(comm + PDO_MAPPING_OFFSET, 0)
        return min(8, sum(dut.read_uint(comm + PDO_MAPPING_OFFSET, s) & 0xFF for s in range(1, count + 1)) // 8)
    found = dut.profile.params_of(fx.FixedTpdoMapping)
    polled = next((p for p in found.polled_tpdos if p.tpdo == comm), None) if found else None
    return polled.rtr_dlc if polled is not None and isinstance(polled.rtr_dlc, int) else 0


def _sent_by_itself(dut, comm: int) -> bool:
    """A TPDO a fixed-layout quirk sends cyclically (e.g. POSITAL 1800h every 2200h ms)."""
    found = dut.profile.params_of(fx.FixedTpdoMapping)
    return found is not None and comm in {spec.tpdo for spec in found.cyclic_tpdos}


def _rtr_tpdo(dut, evidence, settings_journal) -> tuple[int, str]:
    """A TPDO that answers RTR per profile: a polled fixed-layout TPDO (manual), else one that accepts type 253
    (CiA 301), set to 253; skips where the profile declares none."""
    found = dut.profile.quirk(fx.FixedTpdoMapping)
    if found is not None and found.params.polled_tpdos:
        evidence.deviation(found.id, found.quirk.title)
        evidence.rests_on("manual", found.quirk.manual)
        return found.params.polled_tpdos[0].tpdo, "polled"
    tpdo = tpdo_under_test(dut, 2, evidence, settings_journal, [253])
    comm = tpdo.comm
    if not tpdo.writable(2):
        not_applicable(f"{comm:04X}h.02 is fixed")
    tpdo.configure(trans_type=253)
    evidence.rests_on("cia", "CiA 301 §7.5.2.37 (transmission type 253: sent on RTR only)")
    if tpdo.cob_id() & COB_ID_NO_RTR:
        not_applicable(f"{comm:04X}h.01 bit 30 is set (no RTR allowed) although type 253 is accepted")
    return comm, "type 253"


def test_rtr_answered(dut, settings_journal, back_to_preoperational, evidence):
    """A remote frame on the COB-ID of a TPDO that answers RTR (type 253, or polled per manual) makes the device
    send that TPDO within the PDO response time; a type-253 TPDO is not sent on SYNC."""
    comm, how = _rtr_tpdo(dut, evidence, settings_journal)
    cob_id = dut.tpdo.at(comm).can_id()
    dlc = _rtr_dlc(dut, comm)
    dut.nmt.transition("operational", settings_journal, evidence)
    if how == "type 253":
        unasked = _syncs(dut, 2, cob_id)
        assert not unasked, f"{comm:04X}h type 253 sent on SYNC:\n{format_frames(unasked[:5])}"
    # a TPDO that is also sent by itself (POSITAL 1800h: cyclic): ask right after one of its own frames, and wait
    # for the answer less than half its period, so that its next own frame cannot pass for the answer
    window = dut.pdo_answer_s  # an answer the device owes
    own = dut.frames.wait_count(received_on(cob_id), 2, 2.0) if _sent_by_itself(dut, comm) else []
    if len(own) == 2:
        window = min(window, (own[1].timestamp - own[0].timestamp) / 2)
        evidence.note(f"{cob_id:03X}h is also sent by itself (every {(own[1].timestamp - own[0].timestamp) * 1000:.0f}"
                      " ms): the remote frame followed one of its own frames")
    mark = dut.send(cob_id, bytes(dlc), remote=True)
    answer = dut.frames.wait_for(received_on(cob_id), window, mark)
    assert answer is not None, (f"no TPDO on {cob_id:03X}h within {window * 1000:.0f} ms of a remote frame "
                                f"(DLC {dlc}) on it ({how})\n{format_frames(dut.frames.since(mark)[:8])}")
    evidence.measure("RTR to TPDO", round((answer.timestamp - dut.frames.since(mark)[0].timestamp) * 1000, 2), "ms")


def test_rtr_not_answered_without_rtr_bit(dut, settings_journal, back_to_preoperational, evidence):
    """A valid SYNC-driven TPDO whose COB-ID has bit 30 set (no RTR allowed) does not answer a remote frame."""
    evidence.rests_on("cia", "CiA 301 §7.5.2.37 (COB-ID bit 30 = 1: no RTR allowed on this PDO)")
    tpdo = _sync_tpdo(dut, evidence, settings_journal)
    comm, cob = tpdo.comm, tpdo.cob_id()
    if not cob & COB_ID_NO_RTR:
        not_applicable(f"{comm:04X}h.01 = {cob:08X}h allows RTR (bit 30 clear)")
    cob_id = can_id_of(cob)
    dut.nmt.transition("operational", settings_journal, evidence)
    mark = dut.send(cob_id, bytes(_rtr_dlc(dut, comm)), remote=True)
    answers = dut.frames.quiet_period(received_on(cob_id), dut.pdo_silence_s, mark)
    evidence.measure(f"TPDO {cob_id:03X}h frames after a remote frame", len(answers), "frames", 0, 0)
    assert not answers, f"{comm:04X}h.01 = {cob:08X}h (no RTR): answered a remote frame:\n{format_frames(answers)}"


# -- transmission types 0 and 254/255 ---------------------------------------------------------------------
def test_type_0_sends_on_sync_only_after_change(dut, settings_journal, back_to_preoperational, shaft, evidence):
    """Type 0: no TPDO on SYNCs while the position stands, none when it changes, exactly one on the next SYNC."""
    evidence.rests_on("cia", "CiA 301 §7.5.2.37 (type 0: synchronous, acyclic: after an event, on the next SYNC)")
    _need_shaft(shaft, "type 0 (a change of the mapped value)")
    tpdo = _sync_tpdo(dut, evidence, settings_journal, [0])
    comm = tpdo.comm
    if not tpdo.maps_position():
        not_applicable(f"{comm:04X}h maps no position value the shaft could change")
    cob_id = tpdo.can_id()
    dut.nmt.transition("operational", settings_journal, evidence)
    _syncs(dut, 1, cob_id)  # whether the first SYNC after start sends is not this test's business
    standing = _syncs(dut, 3, cob_id)
    assert not standing, f"{comm:04X}h type 0: {len(standing)} TPDO(s) on SYNCs without a change:\n" \
                         f"{format_frames(standing[:5])}"
    mark = dut.frames.mark()
    shaft.turn_by(TURN)
    early = dut.frames.quiet_period(received_on(cob_id), dut.pdo_silence_s, mark)
    assert not early, f"{comm:04X}h type 0 sent on the change itself, before any SYNC:\n{format_frames(early)}"
    first, then = _syncs(dut, 1, cob_id, until_first=True), _syncs(dut, 2, cob_id)  # the first SYNC owes one
    evidence.measure(f"TPDO {cob_id:03X}h frames for 3 SYNCs after one change", len(first) + len(then), "frames",
                     1, 1)
    trace = format_frames(dut.frames.since(mark)[:12])
    assert len(first) == 1, f"{comm:04X}h type 0: {len(first)} TPDO(s) on the first SYNC after a change:\n{trace}"
    assert not then, f"{comm:04X}h type 0: {len(then)} TPDO(s) on the two SYNCs after that one:\n{trace}"


def test_change_of_state_sends_event_tpdo(dut, settings_journal, back_to_preoperational, shaft, evidence):
    """Type 254/255 with event timer 0: the TPDO comes when the position changes and not while it stands."""
    evidence.rests_on("inferred", "CiA 301 §7.5.2.37: 254/255 are event-driven; the event of an encoder's TPDO "
                      "is a change of its position (e.g. WDGA T 8.46); CiA 406 leaves it to the manufacturer")
    tpdo = _event_tpdo(dut, evidence, settings_journal, shaft)
    comm, kind, cob_id = tpdo.comm, tpdo.trans_type, tpdo.can_id()
    dut.nmt.transition("operational", settings_journal, evidence)
    # a TPDO on entering operational is allowed: it may come or not (no event to wait for), so the settle time and
    # the PDO silence window pass before the standing shaft is watched
    dut.frames.quiet_period(lambda m: False, dut.profile.timing.nmt_settle_ms / 1000 + dut.pdo_silence_s)
    standing = dut.frames.quiet_period(received_on(cob_id), dut.pdo_silence_s)
    mark = dut.frames.mark()
    shaft.turn_by(TURN)
    sent = dut.frames.wait_for(received_on(cob_id), _window(dut), mark)
    rests_on = "254/255 with timer 0 are sent on a change of the mapped value (our reading)"
    if standing:
        evidence.inferred_problem(f"{comm:04X}h type {kind}, timer 0: {len(standing)} TPDO(s) while the shaft "
                                  "stood still", rests_on)
    if sent is None:
        evidence.inferred_problem(f"{comm:04X}h type {kind}, timer 0: no TPDO within {_window(dut) * 1000:.0f} ms "
                                  f"of a position change", rests_on)
    evidence.measure(f"TPDO {cob_id:03X}h after a position change", 0 if sent is None else 1, "frames", 1)


# -- SYNC start value and the SYNC counter 1019h ----------------------------------------------------------
def _sync_counter(dut) -> None:
    if dut.profile.entry(SYNC_COUNTER_OVERFLOW, 0) is None:
        not_applicable("the profile has no 1019h (SYNC counter overflow value)")


def test_sync_start_value(dut, settings_journal, tpdo_while_invalid, back_to_preoperational, evidence):
    """1019h = 8, type 1, sub 6 = 5: SYNCs carrying the counters 1..8 give TPDOs on the SYNCs 5..8 only. Sub 6 is
    written (and put back) with the TPDO not valid, as CiA 301 lets a device require."""
    evidence.rests_on("cia", "CiA 301 v4.2.0 §7.5.2.37 (sub 6: the SYNC whose counter equals it is the first "
                             "received; it may change only while the TPDO is not valid)")
    _sync_counter(dut)
    tpdo = tpdo_under_test(dut, 6, evidence, settings_journal, [1])
    comm = tpdo.comm
    overflow, start = 8, 5
    settings_journal.write(SYNC_COUNTER_OVERFLOW, 0, bytes([overflow]))
    tpdo.configure(trans_type=1)
    tpdo.configure_while_invalid(tpdo_while_invalid, sync_start_value=start)
    cob_id = tpdo.can_id()
    dut.nmt.transition("operational", settings_journal, evidence)
    sent = []
    for counter in range(1, overflow + 1):
        mark = dut.send(SYNC_COB_ID, bytes([counter]))
        if counter >= start:
            dut.frames.wait_for(received_on(cob_id), _window(dut), mark)
        else:
            dut.frames.quiet_period(lambda m: False, dut.pdo_silence_s)
        if dut.frames.since(mark, received_on(cob_id)):
            sent.append(counter)
    evidence.measure("SYNC counters followed by a TPDO", len(sent), "SYNCs", overflow - start + 1,
                     overflow - start + 1)
    assert sent == list(range(start, overflow + 1)), (
        f"{comm:04X}h type 1, sub 6 = {start}, 1019h = {overflow}: TPDOs after the SYNCs with counter {sent}, "
        f"expected {list(range(start, overflow + 1))}")


def test_sync_counter_overflow_reserved_values_refused(dut, settings_journal, evidence):
    """1019h refuses 1 and 241..255 (reserved) and keeps its value; where 1006h exists, 1019h is refused while
    1006h is not 0."""
    evidence.rests_on("cia", "CiA 301 §7.5.2.18 (1019h: 0, 2..240; 1 and 241..255 reserved)")
    _sync_counter(dut)
    before = dut.read(SYNC_COUNTER_OVERFLOW, 0)
    settings_journal.remember(SYNC_COUNTER_OVERFLOW, 0, before)
    accepted = []
    for value in (1, 241, 255):
        what = f"1019h = {value} (reserved)"
        response = dut.expect_abort(sdo_frames.expedited_download_request(SYNC_COUNTER_OVERFLOW, 0, bytes([value])))
        if not response.is_abort:
            accepted.append(what)
            dut.write(SYNC_COUNTER_OVERFLOW, 0, before)
            continue
        _judge_code(dut, response, {SdoAbortCode.VALUE_INVALID}, what, evidence,
                    "06090030h (value range of parameter exceeded); " + ANY_ABORT)
    assert not accepted, "accepted: " + "; ".join(accepted)
    assert dut.read(SYNC_COUNTER_OVERFLOW, 0) == before, "1019h changed by the refused writes"
    cycle = dut.profile.entry(COMMUNICATION_CYCLE_PERIOD, 0)
    if cycle is None or not cycle.writable:
        evidence.note("no writable 1006h: the rule 'writable only while 1006h = 0' is not checked")
        return
    settings_journal.write(COMMUNICATION_CYCLE_PERIOD, 0, _u32(10000))
    what = "1019h = 2 while 1006h = 10000 us"
    response = dut.expect_abort(sdo_frames.expedited_download_request(SYNC_COUNTER_OVERFLOW, 0, b"\x02"))
    if not response.is_abort:
        dut.write(COMMUNICATION_CYCLE_PERIOD, 0, _u32(0))
        dut.write(SYNC_COUNTER_OVERFLOW, 0, before)
    assert response.is_abort, f"{what}: accepted; {ANY_ABORT}"
    _judge_code(dut, response, expected_aborts(dut, "wrong_state", evidence), what, evidence,
                "CiA's code for the present device state; " + ANY_ABORT)


# -- writes in pre-operational only (quirk) ----------------------------------------------------------------
def _other_value(dut, comm: int, covered) -> tuple[int, int, int] | None:
    """(sub, size, a value other than the current one) of a writable sub of ``comm`` the quirk covers."""
    for sub in (5, 2, 1):
        entry = dut.profile.entry(comm, sub)
        domain = declared_domain(dut.profile, comm, sub)
        if entry is None or not entry.writable or domain is None or not covered(comm, sub):
            continue
        size = len(dut.read(comm, sub))
        current = int.from_bytes(dut.read(comm, sub), "little")
        if sub == 1:
            return sub, size, current ^ COB_ID_INVALID  # valid <-> not valid: bits 0-29 stay
        other = next((v for v in (current + 1, current - 1, 1) if v != current and v in domain), None)
        if other is not None:
            return sub, size, other
    return None


def test_tpdo_parameters_writable_in_preoperational_only(dut, settings_journal, back_to_preoperational, evidence):
    """Documented quirk: a write to a listed TPDO communication object or entry is refused in operational (the
    value stays) and accepted in pre-operational (then put back). Every quirk with that effect counts (a
    manual may say it in several sections)."""
    changes = []  # (comm, sub, size, value, codes wanted)
    for each in dut.profile.quirks_with(fx.WritesPreopOnly):
        params = each.params
        comms = sorted(i for i in dut.profile.objects if 0x1800 <= i <= 0x19FF
                       and any(params.covers(i, sub) for sub in (1, 2, 5)))
        found = [(comm, *other) for comm in comms if (other := _other_value(dut, comm, params.covers)) is not None]
        if not found:
            continue
        evidence.deviation(each.id, each.quirk.title)
        evidence.rests_on("manual", each.quirk.manual)
        wanted = ({params.abort_code} if params.abort_code is not None
                  else expected_aborts(dut, "wrong_state", evidence))
        changes += [(*change, wanted) for change in found]
    if not changes:
        not_applicable("no quirk writes_preop_only covers a writable TPDO communication entry the test "
                    "may change")
    for comm, sub, _, _, _ in changes:
        settings_journal.remember(comm, sub)
    dut.nmt.transition("operational", settings_journal, evidence)
    problems = []
    for comm, sub, size, value, wanted in changes:
        before = dut.read(comm, sub)
        what = f"{comm:04X}h.{sub:02X} = {value:#x} in operational"
        response = dut.expect_abort(sdo_frames.expedited_download_request(comm, sub, value.to_bytes(size, "little")))
        evidence.note(f"{what}: {response.describe()}")
        if not response.is_abort:
            problems.append(f"{what}: accepted")
        elif not abort_accepted(dut, response, wanted):
            evidence.inferred_problem(f"{what}: {abort_name(response.abort_code or 0)}", "the quirk's abort code")
        if dut.read(comm, sub) != before and response.is_abort:
            problems.append(f"{what}: refused, but the value changed")
    dut.nmt.back_to_preoperational()
    for comm, sub, size, value, _ in changes:
        dut.write(comm, sub, value.to_bytes(size, "little"))  # raises if refused in pre-operational
    assert not problems, "; ".join(problems)


# -- gating: no trigger sends a TPDO outside operational ----------------------------------------------------
@pytest.mark.parametrize("state", ["pre-operational", "stop"], ids=["pre-operational", "stopped"])
@pytest.mark.parametrize("trigger", ["SYNC", "change of state"])
def test_tpdo_silent_after_leaving_operational(dut, settings_journal, back_to_preoperational, shaft, evidence,
                                              trigger, state):
    """A TPDO sent on SYNC (type 1) or on a change of state sends nothing once the device left operational,
    although SYNCs arrive and the shaft turns, and is sent again after NMT start."""
    evidence.rests_on("cia", NO_PDO_OUTSIDE_OPERATIONAL)
    if trigger == "SYNC":
        tpdo = _sync_tpdo(dut, evidence, settings_journal, [1])
    else:
        tpdo = _event_tpdo(dut, evidence, settings_journal, shaft)
    comm, cob_id = tpdo.comm, tpdo.can_id()
    is_this = received_on(cob_id)

    def stimulate(expected: bool = True) -> list[can.Message]:
        """Three triggers, each followed by a PDO silence window, or where a TPDO is ``expected`` the PDO answer
        window cut short by the first TPDO: the TPDOs they brought."""
        mark = dut.frames.mark()
        for _ in range(3):
            if trigger == "SYNC":
                dut.send_sync()
            else:
                shaft.turn_by(TURN)
            if expected and dut.frames.wait_for(is_this, dut.pdo_answer_s, mark) is not None:
                break
            if not expected:
                dut.frames.quiet_period(lambda m: False, dut.pdo_silence_s)
        return dut.frames.since(mark, is_this)

    dut.nmt.transition("operational", settings_journal, evidence)
    running = stimulate()
    if trigger != "SYNC" and not running:
        not_judged(Hold.NO_TPDO_ON_CHANGE, f"{comm:04X}h sent nothing on a change in operational (see "
                    "test_change_of_state_sends_event_tpdo), so its silence outside operational proves nothing")
    assert running, f"{comm:04X}h: no TPDO on {cob_id:03X}h on {trigger} in operational"
    sent = dut.nmt.command(state)
    # a TPDO after the heartbeat shows the state is this state's, also after the window (dut/link/late_frames.py)
    dut.frames.late.open_state(dut.node_id, state, is_this, f"TPDO {cob_id:03X}h",
                               NO_PDO_OUTSIDE_OPERATIONAL)
    dut.nmt.settle(sent, state)  # the state change: until the heartbeat reports it, at most the settle time
    late = stimulate(expected=False)
    evidence.measure(f"TPDO {cob_id:03X}h frames on {trigger} in {state}", len(late), "frames", 0, 0)
    assert not late, f"{len(late)} TPDO(s) on {cob_id:03X}h on {trigger} after NMT {state}:\n{format_frames(late[:5])}"
    dut.nmt.transition("operational", settings_journal, evidence)
    assert stimulate(), f"no TPDO on {cob_id:03X}h on {trigger} after NMT start again"
