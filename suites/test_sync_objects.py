"""The SYNC COB-ID 1005h (CiA 301 v4.2.0 §7.5.2.5): bit 30 (generate SYNC) as the profile declares the device
(capabilities.sync_producer: refused by a device that cannot produce SYNC, accepted by a producer, either where the
profile says "may"), a producer's SYNC every 1006h µs and none with 1006h = 0, restricted CAN-IDs refused, and SYNC
taken on the CAN-ID 1005h names.

Not here: the SYNC counter 1019h (its reserved values, its write while 1006h is not 0, the SYNC start value) is
checked with TPDOs in test_pdo_comm.py; a SYNC of the wrong length (EMCY 8240h) in test_emcy.py. 1006h
(communication cycle period) is written only by the producer test (put back to 0 first, so the SYNCs stop, then
1005h; an error the device raised meanwhile, e.g. a SYNC time-out, cleared by reset communication: fixture
no_error_left); 1007h (synchronous window) is declared by no profile; bit 31 of 1005h is "do not care" in CiA 301,
nothing to check. Every 1005h value a test changes is put back (on a SIKO each write is stored by the device itself, on
a WayCon only by its store command, which no test sends).
"""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import (
    COB_ID_SYNC_GENERATE,
    COMMUNICATION_CYCLE_PERIOD,
    RESTRICTED_CAN_IDS,
    SYNC_COB_ID_OBJECT,
    SdoAbortCode,
    can_id_of,
    is_restricted_can_id,
    with_can_id,
)
from encoder_conformance.dut.link import format_frames, received_on
from encoder_conformance.dut.sdo import SdoResponse, abort_name, sdo_frames
from encoder_conformance.plugin.skips import not_applicable
from encoder_conformance.plugin.suite_helpers import abort_accepted, tpdo_under_test
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.value_domain import declared_domain

pytestmark = [pytest.mark.spec("CiA 301 v4.2.0 §7.5.2.5 object 1005h (COB-ID SYNC)"),
              pytest.mark.requires("sync_consumer"), pytest.mark.usefixtures("no_error_left")]

CLAUSE = "CiA 301 v4.2.0 §7.5.2.5 object 1005h (COB-ID SYNC)"
PRODUCER_PERIOD_US = 10000  # 1006h for the producer test: 10 ms
PRODUCER_SYNCS = 3
CODE_BASIS = "06090030h, the code CiA 301 gives for 1005h (CTT Other 10); any abort refuses the write"
#: the ends of every restricted range (CiA 301 §7.3.5)
RESTRICTED_PROBES = sorted({c for ids in RESTRICTED_CAN_IDS for c in (ids.start, ids.stop - 1)})
OTHER_SYNC_CAN_ID = 0x0FF  # not restricted; the EMCY CAN-ID of node 127, rarely used on a bench


@pytest.fixture
def sync_cob_id(dut, settings_journal) -> int:
    """1005h as found (put back after the test); skips where it cannot be written."""
    entry = dut.profile.entry(SYNC_COB_ID_OBJECT, 0)
    if entry is None or not entry.writable:
        not_applicable("the profile has no writable 1005h")
    found = dut.read_uint(SYNC_COB_ID_OBJECT)
    settings_journal.remember(SYNC_COB_ID_OBJECT, 0, found.to_bytes(4, "little"))
    return found


def _write(dut, value: int) -> SdoResponse:
    return dut.expect_abort(sdo_frames.expedited_download_request(SYNC_COB_ID_OBJECT, 0, value.to_bytes(4, "little")))


def _judge_code(dut, response: SdoResponse, value: int, what: str, evidence) -> None:
    """06090030h; also 06090031h/06090032h for a value outside the range the profile declares for 1005h."""
    wanted = {SdoAbortCode.VALUE_INVALID}
    domain = declared_domain(dut.profile, SYNC_COB_ID_OBJECT, 0)
    if domain is not None and value not in domain:
        wanted |= {SdoAbortCode.VALUE_HIGH, SdoAbortCode.VALUE_LOW}
    if not abort_accepted(dut, response, wanted):
        evidence.inferred_problem(f"{what}: aborted with {abort_name(response.abort_code or 0)}, expected "
                                  + " or ".join(abort_name(c) for c in sorted(wanted)), CODE_BASIS)


def test_sync_generate_bit_refused(dut, sync_cob_id, evidence):
    """1005h with bit 30 set (the device generates SYNC): refused, 1005h unchanged, by a device the profile declares
    unable to produce SYNC; accepted by a producer; either where the profile says "may" (what came is noted)."""
    producer = dut.profile.capabilities.sync_producer
    evidence.rests_on("cia", CLAUSE + ': a device that cannot generate SYNC refuses bit 30 = 1 with 06090030h; the '
                      f"profile declares capabilities.sync_producer = {producer}")
    value = sync_cob_id | COB_ID_SYNC_GENERATE
    what = f"1005h = {value:08X}h (bit 30: generate SYNC)"
    response = _write(dut, value)
    if not response.is_abort:
        dut.write(SYNC_COB_ID_OBJECT, 0, sync_cob_id.to_bytes(4, "little"))  # bit 30 off again (1006h untouched)
        assert producer, f"{what}: accepted ({response.describe()}); the profile says the device cannot produce SYNC"
        evidence.note(f"{what}: accepted (a SYNC producer; capabilities.sync_producer = {producer}), put back")
        return
    assert producer is not True, f"{what}: refused ({response.describe()}); the profile declares a SYNC producer"
    evidence.note(f"{what}: refused ({response.describe()})")
    _judge_code(dut, response, value, what, evidence)
    after = dut.read_uint(SYNC_COB_ID_OBJECT)
    assert after == sync_cob_id, f"after the refused {what}: 1005h reads {after:08X}h"


def test_sync_producer_sends_every_cycle(dut, sync_cob_id, settings_journal, evidence):
    """A SYNC producer (1005h bit 30 accepted) with 1006h = 10 ms sends SYNC on the 1005h CAN-ID, and none once 1006h
    is 0 again; 1006h, then 1005h, are put back. Skipped where bit 30 is refused (the test above judges that)."""
    evidence.rests_on("cia", "CiA 301 v4.2.0 §7.5.2.5 (1005h bit 30: the device generates SYNC), §7.5.2.6 (1006h: "
                             "the SYNC period in µs; 0 = no SYNC transmitted)")
    if not dut.profile.capabilities.sync_producer:
        not_applicable("the profile declares no SYNC producer (capabilities.sync_producer)")
    cycle = dut.profile.entry(COMMUNICATION_CYCLE_PERIOD, 0)
    if cycle is None or not cycle.writable:
        not_applicable("the profile has no writable 1006h (communication cycle period)")
    if dut.read_uint(COMMUNICATION_CYCLE_PERIOD):
        not_applicable("1006h is not 0 as found (the bus's SYNC may be this device's)")
    generating = sync_cob_id | COB_ID_SYNC_GENERATE
    if _write(dut, generating).is_abort:
        not_applicable(f"1005h = {generating:08X}h refused (the device does not generate SYNC)")
    can_id = can_id_of(sync_cob_id)
    is_own_sync = received_on(can_id)

    settings_journal.remember(COMMUNICATION_CYCLE_PERIOD, 0)
    mark = dut.frames.mark()
    try:
        dut.write(COMMUNICATION_CYCLE_PERIOD, 0, PRODUCER_PERIOD_US.to_bytes(4, "little"))
        period_s = PRODUCER_PERIOD_US / 1e6
        # frames that must come: the first within the PDO answer window of the write, each further one a period
        # later (one period spare); the wait ends at the last of them
        window = (PRODUCER_SYNCS + 1) * period_s + dut.pdo_answer_s
        syncs = dut.frames.wait_count(is_own_sync, PRODUCER_SYNCS, window, mark)
    finally:
        dut.write(COMMUNICATION_CYCLE_PERIOD, 0, bytes(4))  # stop the SYNCs before anything else
    stopped = dut.frames.mark()
    late = dut.frames.quiet_period(is_own_sync, 2 * period_s + dut.pdo_silence_s, stopped)
    dut.forbid_until_written(is_own_sync, f"a SYNC on {can_id:03X}h", "1006h = 0",
                             "CiA 301 §7.5.2.6 (1006h = 0: no SYNC transmitted)", (COMMUNICATION_CYCLE_PERIOD, 0),
                             bytes(4))
    dut.write(SYNC_COB_ID_OBJECT, 0, sync_cob_id.to_bytes(4, "little"))
    evidence.measure(f"SYNCs on {can_id:03X}h within {window * 1000:.0f} ms of 1006h = {PRODUCER_PERIOD_US} us",
                     len(syncs), "frames", PRODUCER_SYNCS, None)
    assert len(syncs) >= PRODUCER_SYNCS, (
        f"1005h = {generating:08X}h, 1006h = {PRODUCER_PERIOD_US} us: {len(syncs)} SYNC(s) on {can_id:03X}h within "
        f"{window * 1000:.0f} ms\n{format_frames(dut.frames.since(mark)[-8:])}")
    assert not late, f"1006h = 0: still {len(late)} SYNC(s) on {can_id:03X}h\n{format_frames(late[:5])}"


def test_sync_restricted_can_id_refused(dut, sync_cob_id, evidence):
    """1005h with a restricted CAN-ID (the ends of 000h-07Fh, 101h-180h, 581h-5FFh, 601h-67Fh, 6E0h-7FFh) is
    refused and keeps its value; where the manual lets 1005h take any CAN-ID of a range (quirk), the answers are
    recorded."""
    evidence.rests_on("cia", "CiA 301 §7.3.5 (restricted CAN-IDs); CTT Other 10")
    found = dut.profile.quirk(fx.SyncCobIdAnyCanId)
    accepted = []
    for can_id in RESTRICTED_PROBES:
        value = with_can_id(sync_cob_id, can_id)
        what = f"1005h = {value:08X}h (restricted CAN-ID {can_id:03X}h)"
        response = _write(dut, value)
        evidence.note(f"{can_id:03X}h: {response.describe()}")
        if not response.is_abort:
            accepted.append(what)
            dut.write(SYNC_COB_ID_OBJECT, 0, sync_cob_id.to_bytes(4, "little"))
        else:
            _judge_code(dut, response, value, what, evidence)
    if found is not None:
        evidence.deviation(found.id, found.quirk.title)
        evidence.note(f"quirk {found.id}: {len(accepted)} of {len(RESTRICTED_PROBES)} restricted CAN-IDs accepted "
                      "(recorded, not judged)")
        return
    evidence.measure("restricted CAN-IDs refused", len(RESTRICTED_PROBES) - len(accepted), "",
                     len(RESTRICTED_PROBES), len(RESTRICTED_PROBES))
    assert not accepted, "accepted: " + "; ".join(accepted)
    assert dut.read_uint(SYNC_COB_ID_OBJECT) == sync_cob_id, "1005h changed by the refused writes"


def test_sync_taken_on_its_cob_id(dut, sync_cob_id, settings_journal, back_to_preoperational, evidence):
    """With 1005h = 0FFh a synchronous TPDO (type 1) answers a SYNC on 0FFh, and no longer one on the old SYNC
    CAN-ID."""
    evidence.rests_on("cia", CLAUSE + " (bits 0-10: the CAN-ID of the SYNC the device consumes)")
    assert not is_restricted_can_id(OTHER_SYNC_CAN_ID)
    other = with_can_id(sync_cob_id, OTHER_SYNC_CAN_ID)
    domain = declared_domain(dut.profile, SYNC_COB_ID_OBJECT, 0)
    if domain is not None and other not in domain:
        not_applicable(f"the profile declares 1005h in {domain}, without {other:08X}h")
    chosen = tpdo_under_test(dut, 2, evidence, settings_journal, [1, *range(2, 241)])
    if chosen.trans_type != 1:
        not_applicable(f"{chosen.comm:04X}h is sent on every {chosen.trans_type}th SYNC only (fixed), "
                    "not on each")
    chosen.configure(trans_type=1)
    tpdo = chosen.can_id()
    old = can_id_of(sync_cob_id)
    settings_journal.write(SYNC_COB_ID_OBJECT, 0, other.to_bytes(4, "little"))
    dut.nmt.transition("operational", settings_journal, evidence)
    settle = dut.profile.timing.nmt_settle_ms / 1000
    answer, window = chosen.answer_s + settle, chosen.silence_s + settle  # a TPDO that must come; one that must not

    is_tpdo = chosen.frames(tpdo)

    mark = dut.send(OTHER_SYNC_CAN_ID)
    answered = dut.frames.wait_for(is_tpdo, answer, mark)
    assert answered is not None, (f"1005h = {OTHER_SYNC_CAN_ID:03X}h: no TPDO on {tpdo:03X}h within "
                                  f"{answer * 1000:.0f} ms of a SYNC on {OTHER_SYNC_CAN_ID:03X}h\n"
                                  f"{format_frames(dut.frames.since(mark))}")
    mark = dut.send(old)
    stray = dut.frames.quiet_period(is_tpdo, window, mark)
    assert not stray, (f"1005h = {OTHER_SYNC_CAN_ID:03X}h: TPDO {tpdo:03X}h after a frame on the old SYNC CAN-ID "
                       f"{old:03X}h\n{format_frames(stray)}")
