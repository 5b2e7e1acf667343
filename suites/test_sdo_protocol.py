"""SDO protocol, byte-exact: expedited sizes, size mismatches, segmented transfers step by step.

CiA 301 §7.2.4.3 (SDO protocols), table 22 (abort codes); CTT cases SDO 08/09 (too long / too
short), 13-18 (segmented, wrong toggle bit). Every request goes out as the frame a step names
(``dut/sdo/sdo_client.py``); every initiate response must echo the request's multiplexer. Abort codes:
CiA's code (or the manual's), else one the CiA conformance test tool accepts; any other code is a
warning (inferred), a write that is confirmed is a failure. Only entries that are harmless to write
are written (heartbeat and guard times, event timers, transmission types), each put back.
"""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import SDO_ABORT, SdoAbortCode
from encoder_conformance.coverage import Hold
from encoder_conformance.dut.link import SdoAborted
from encoder_conformance.dut.sdo import SdoProtocolClient, SdoResponse, abort_name, echoes, upload_request
from encoder_conformance.plugin.skips import not_applicable, not_judged
from encoder_conformance.plugin.suite_helpers import assert_one_answer, expected_aborts, judge_refusal
from encoder_conformance.profile import datatypes

pytestmark = pytest.mark.spec("CiA 301 §7.2.4.3 (SDO protocols)")

#: entries whose value may be written (and put back) without effect beyond timing: harmless to rewrite
HARMLESS = [(0x1017, 0), (0x100C, 0), (0x6200, 0), (0x1800, 5), (0x1801, 5), (0x100D, 0), (0x1800, 2),
            (0x1801, 2), (0x1016, 1)]
#: the CiA conformance test tool's accepted codes for too long (SDO 08) and too short (SDO 09) data
CTT_TOO_LONG = {SdoAbortCode.LENGTH_MISMATCH, SdoAbortCode.LENGTH_HIGH, SdoAbortCode.GENERAL_ERROR}
CTT_TOO_SHORT = {SdoAbortCode.LENGTH_MISMATCH, SdoAbortCode.LENGTH_LOW, SdoAbortCode.GENERAL_ERROR}
EXPEDITED = "CiA 301 §7.2.4.3.3 (initiate SDO download), §7.2.4.3.6 (initiate SDO upload)"
SEGMENTED = "CiA 301 §7.2.4.3.4-7 (SDO segment download / upload: toggle bit, n, c)"


@pytest.fixture
def sdo(dut) -> SdoProtocolClient:
    return dut.sdo.protocol()


def _harmless(profile, size: int) -> tuple[int, int] | None:
    """The first harmless entry of ``size`` bytes the profile declares readable and writable."""
    for index, sub in HARMLESS:
        entry = profile.entry(index, sub)
        if entry is not None and entry.writable and entry.readable and datatypes.size_bytes(entry.type) == size:
            return index, sub
    return None


def _target(dut) -> tuple[int, int]:
    """A harmless 16-bit entry to write (1017h where declared), or skip."""
    found = _harmless(dut.profile, 2)
    if found is None:
        not_applicable("the profile declares no harmless writable 16-bit entry (1017h, 100Ch, ...)")
    return found


def _new_value(dut, key: tuple[int, int], current: bytes) -> bytes:
    """A value other than ``current`` within the entry's declared range (1234 where it fits)."""
    entry = dut.profile.entry(*key)
    value = 1234 if int.from_bytes(current, "little") != 1234 else 1235
    if entry.max is not None and value > entry.max:
        value = int(entry.max) if int.from_bytes(current, "little") != entry.max else int(entry.max) - 1
    return value.to_bytes(len(current), "little")


def _readable_of_size(profile, size: int) -> tuple[int, int] | None:
    """A readable entry of exactly ``size`` bytes, a static one where there is one."""
    found = [(e.dynamic, i, s) for i, s, _, e in profile.iter_entries()
             if e.readable and datatypes.size_bytes(e.type) == size]
    return min(found)[1:] if found else None


def _long_entries(profile) -> list[tuple[int, int, int | None]]:
    """Readable entries that cannot go expedited (over 4 bytes, strings, domains): (index, sub, size or None)."""
    return [(i, s, datatypes.size_bytes(e.type)) for i, s, _, e in profile.iter_entries()
            if e.readable and (datatypes.size_bytes(e.type) or 5) > 4]


def _longest(dut) -> tuple[int, int]:
    longest = [(i, s) for i, s, _ in _long_entries(dut.profile)]
    if not longest:
        not_applicable("every object the profile declares fits an expedited transfer (4 bytes)")
    sizes = {}
    for key in longest:
        try:
            sizes[key] = len(dut.read(*key))
        except SdoAborted:  # the entry's own verdict: test_segmented_upload_of_every_long_entry
            continue
    if not sizes:
        not_judged(Hold.NO_READABLE_LONG_ENTRY, "the read of every entry over 4 bytes aborts (judged by "
                    "test_segmented_upload_of_every_long_entry)")
    return max(sizes, key=lambda key: sizes[key])


def _unchanged(dut, key: tuple[int, int], before: bytes, what: str) -> None:
    after = dut.read(*key)
    assert after == before, f"{what}: {key[0]:04X}h.{key[1]:02X} changed from {before.hex(' ')} to {after.hex(' ')}"


# -- expedited --------------------------------------------------------------------------------------
def test_expedited_upload_byte_exact(dut, sdo, evidence):
    """Initiate upload of a 1-, 2-, 3- and 4-byte entry (where declared): scs 2, e=1, the multiplexer echoed, and
    with s=1 the n bits giving the entry's size."""
    evidence.rests_on("cia", EXPEDITED)
    problems = []
    for size in (1, 2, 3, 4):
        key = _readable_of_size(dut.profile, size)
        if key is None:
            continue
        name = f"{key[0]:04X}h.{key[1]:02X} ({size} bytes)"
        request = upload_request(*key)
        response = sdo.request(request)
        if response is None or response.is_abort or response.scs != 2 or not response.raw[0] & 0x02:
            problems.append(f"{name}: {response.describe() if response else 'no response'}, expected an expedited "
                            "upload response")
        elif not echoes(request, response.raw):
            problems.append(f"{name}: the response {response.describe()} names another entry")
        elif response.raw[0] & 0x01 and response.expedited_size != size:
            problems.append(f"{name}: n says {response.expedited_size} bytes")
        elif not response.raw[0] & 0x01:
            evidence.note(f"{name}: the device does not indicate the size (s=0); CiA 301 allows it")
    assert not problems, "\n".join(problems)


def test_expedited_download_byte_exact(dut, sdo, settings_journal, evidence):
    """Initiate download with e=1, s=1 of a harmless 1-, 2- and 4-byte entry (where declared): confirmed (60h, the
    multiplexer echoed) and read back (the 2-byte entry with a new value, the others with their own)."""
    evidence.rests_on("cia", EXPEDITED)
    keys = {size: key for size in (1, 2, 4) if (key := _harmless(dut.profile, size)) is not None}
    if not keys:
        not_applicable("no harmless writable entry of 1, 2 or 4 bytes (see HARMLESS)")
    problems = []
    for size, key in keys.items():
        current = dut.read(*key)
        value = _new_value(dut, key, current) if size == 2 else current
        settings_journal.remember(*key, current)
        response = sdo.expedited_download(*key, value)
        name = f"write of {value.hex(' ')} to {key[0]:04X}h.{key[1]:02X}"
        if response is None or response.raw[0] != 0x60:
            problems.append(f"{name}: {response.describe() if response else 'no response'}, expected 60h")
        elif not echoes(upload_request(*key), response.raw):
            problems.append(f"{name}: the confirmation {response.describe()} names another entry")
        elif dut.read(*key) != value:
            problems.append(f"{name}: reads back {dut.read(*key).hex(' ')}")
    assert not problems, "\n".join(problems)


def test_expedited_download_without_size_indicator(dut, sdo, settings_journal, evidence):
    """e=1, s=0 ("d contains an unspecified number of bytes"): answered; where confirmed (echoing the entry), the
    entry holds the value at its own size. That the server takes its own size rather than refusing is our reading
    (python-canopen's server, for one, refuses: a warning)."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.3 (e=1, s=0: d contains unspecified number of bytes)")
    key = _target(dut)
    current = dut.read(*key)
    value = _new_value(dut, key, current)
    settings_journal.remember(*key, current)
    response = sdo.expedited_download(*key, value + b"\x00\x00", size_indicated=False)
    assert response is not None, "no response to an expedited download without size indicator"
    if response.is_abort:
        evidence.inferred_problem(f"{key[0]:04X}h.{key[1]:02X} written with s=0: {response.describe()}",
                                  "CiA 301 §7.2.4.3.3 lets the client leave the size open; we read it as the "
                                  "server taking the entry's own size")
        _unchanged(dut, key, current, "a refused download without size indicator")
        return
    assert response.raw[0] == 0x60, f"{key[0]:04X}h.{key[1]:02X} with s=0: {response.describe()}"
    assert echoes(upload_request(*key), response.raw), f"the confirmation {response.describe()} names another entry"
    assert dut.read(*key) == value


def _mismatch_target(dut, longer: bool) -> tuple[tuple[int, int], int]:
    """A harmless entry and a length one byte off its size that still fits an expedited frame (1..4 bytes)."""
    for index, sub in HARMLESS:
        entry = dut.profile.entry(index, sub)
        size = datatypes.size_bytes(entry.type) if entry is not None and entry.writable and entry.readable else None
        if size is not None and 1 <= size + (1 if longer else -1) <= 4:
            return (index, sub), size + (1 if longer else -1)
    not_applicable("no harmless writable entry of a size the test can miss by one byte (see HARMLESS)")


@pytest.mark.parametrize("longer", [False, True], ids=["too-short", "too-long"])
def test_expedited_download_size_mismatch_refused(dut, sdo, longer, settings_journal, evidence):
    """An entry written with one byte fewer or more than its data type is refused (06070013h / 06070012h) and
    keeps its value (CTT SDO 08/09)."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.17 table 22 (06070010h, 06070012h, 06070013h)")
    key, length = _mismatch_target(dut, longer)
    current = dut.read(*key)
    settings_journal.remember(*key, current)
    situation, tolerated = ("length_high", CTT_TOO_LONG) if longer else ("length_low", CTT_TOO_SHORT)
    response = sdo.expedited_download(*key, (current * 2)[:length])
    what = f"{length}-byte write to {len(current)}-byte {key[0]:04X}h.{key[1]:02X}"
    judge_refusal(dut, response, expected_aborts(dut, situation, evidence), tolerated, what, evidence)
    _unchanged(dut, key, current, what)


# -- segmented --------------------------------------------------------------------------------------
@pytest.mark.requires("segmented_sdo")
def test_segmented_upload_of_every_long_entry(dut, sdo, evidence):
    """Every entry over 4 bytes (strings, 64-bit values) uploads segment by segment: toggles alternate from 0, the
    size announced is the size carried, and the initiate response echoes the multiplexer (CTT SDO 13, 16)."""
    evidence.rests_on("cia", SEGMENTED)
    entries = _long_entries(dut.profile)
    if not entries:
        not_applicable("every object the profile declares fits an expedited transfer (4 bytes)")
    problems = []
    for index, sub, size in entries:
        result = sdo.upload(index, sub)
        if result.abort is not None:
            problems.append(f"{index:04X}h.{sub:02X}: {result.abort.describe()}")
        problems += [f"{index:04X}h.{sub:02X}: {text}" for text in result.problems]
        if size is not None and result.abort is None and len(result.data) != size:
            problems.append(f"{index:04X}h.{sub:02X}: {len(result.data)} bytes, the type has {size}")
        evidence.note(f"{index:04X}h.{sub:02X}: {len(result.data)} bytes in {len(result.responses) - 1} segment(s)")
    assert not problems, "\n".join(problems)


@pytest.mark.requires("segmented_sdo")
def test_segmented_upload_wrong_toggle_aborts(dut, sdo, evidence):
    """An upload segment request whose toggle bit is not 0 (the first) is refused with 05030000h (CTT SDO 17)."""
    evidence.rests_on("cia", SEGMENTED + "; §7.2.4.3.17 05030000h")
    key = _longest(dut)
    first = sdo.initiate_upload(*key)
    if first is None or first.is_abort or first.raw[0] & 0x02:
        not_applicable(f"{key[0]:04X}h.{key[1]:02X} came expedited")
    response = sdo.upload_segment(toggle=1)
    judge_refusal(dut, response, {SdoAbortCode.TOGGLE_BIT}, set(), "upload segment with toggle bit 1 first", evidence)
    assert response is not None
    assert echoes(upload_request(*key), response.raw), f"the abort {response.describe()} names another entry"


@pytest.mark.requires("segmented_sdo")
def test_segmented_download(dut, sdo, settings_journal, evidence):
    """A 16-bit entry written by segmented download (CTT SDO 15): 60h echoing it, one segment with n=5, c=1
    confirmed with toggle 0, and the value read back."""
    evidence.rests_on("cia", SEGMENTED)
    key = _target(dut)
    current = dut.read(*key)
    value = _new_value(dut, key, current)
    settings_journal.remember(*key, current)
    result = sdo.download(*key, value)
    assert result.ok, f"segmented download of {value.hex(' ')} to {key[0]:04X}h.{key[1]:02X}:\n{result.describe()}"
    assert dut.read(*key) == value


@pytest.mark.requires("segmented_sdo")
def test_segmented_download_wrong_toggle_aborts(dut, sdo, settings_journal, evidence):
    """A download segment whose toggle bit is not 0 (the first) is refused with 05030000h; nothing is written."""
    evidence.rests_on("cia", SEGMENTED + "; §7.2.4.3.17 05030000h")
    key = _target(dut)
    current = dut.read(*key)
    settings_journal.remember(*key, current)
    started = sdo.initiate_download(*key, 2)
    assert started is not None, "no response to initiate download"
    assert started.raw[0] == 0x60, f"initiate segmented download refused: {started.describe()}"
    response = sdo.download_segment(_new_value(dut, key, current), toggle=1, last=True)
    judge_refusal(dut, response, {SdoAbortCode.TOGGLE_BIT}, set(), "download segment with toggle bit 1 first", evidence)
    _unchanged(dut, key, current, "download segment with the wrong toggle bit")


@pytest.mark.requires("segmented_sdo")
def test_segmented_download_size_mismatch_refused(dut, sdo, settings_journal, evidence):
    """A segmented download of 3 bytes (size indicated 3) to a 16-bit entry is refused, by one answer (an abort, not a
    confirmation and then an abort); the entry keeps its value."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.17 table 22 (06070010h, 06070012h); §7.2.4.3.4-7 (each download "
                             "segment confirmed once)")
    key = _target(dut)
    current = dut.read(*key)
    settings_journal.remember(*key, current)
    started = sdo.initiate_download(*key, 3)
    assert started is not None, "no response to initiate download"
    what = f"3 bytes by segmented download to 16-bit {key[0]:04X}h.{key[1]:02X}"
    # refused at once from the size indicated, or after the segment: by one answer (§7.2.4.3.17)
    mark = dut.frames.mark()
    response = started if started.is_abort else sdo.download_segment(current + current[:1], toggle=0, last=True)
    if not started.is_abort:
        assert_one_answer(*sdo.exchange_since(mark), what)
    judge_refusal(dut, response, expected_aborts(dut, "length_high", evidence), CTT_TOO_LONG, what, evidence)
    _unchanged(dut, key, current, "segmented download of 3 bytes")


# -- transfers interrupted --------------------------------------------------------------------------
def _open_upload(dut, sdo) -> tuple[int, int]:
    """A segmented upload of the longest entry, initiated and left open after its first segment."""
    key = _longest(dut)
    first = sdo.initiate_upload(*key)
    assert first is not None, f"no response to the upload of {key[0]:04X}h.{key[1]:02X}"
    if first.is_abort or first.raw[0] & 0x02:
        not_applicable(f"{key[0]:04X}h.{key[1]:02X} came as {first.describe()}")
    segment = sdo.upload_segment(toggle=0)
    assert segment is not None, "no response to the first upload segment request"
    return key


#: what an abort names (open readings sdo-request-while-transfer-open, sdo-request-taken-by-open-transfer)
ABORT_NAMES_ITS_TRANSFER = ("CiA 301 §7.2.4.3.17 (abort SDO transfer: m is the multiplexer of the transfer "
                            "aborted); §7.2.4.2: either side may abort at any time")


def _next_initiate_served(dut, sdo, evidence, what: str, open_key: tuple[int, int] | None = None) -> None:
    """After an interrupted transfer, an upload of 1000h gets an answer echoing it. Where ``open_key``'s transfer
    was still open, the device may first abort that one (an abort naming it), and may take the request as a wrong
    frame of it and leave it unanswered: then the request, sent again, is answered. That it is served, not
    refused, is our reading (a warning)."""
    request = upload_request(0x1000, 0)
    mark = dut.frames.mark()
    response = sdo.request(request)
    frames = [bytes(m.data) for m in dut.frames.since(mark, sdo.is_response)]
    before = frames[: frames.index(response.raw)] if response is not None and response.raw in frames else frames
    ended = [raw for raw in before
             if open_key is not None and raw[0] == SDO_ABORT and raw[1:4] == request_mux(open_key)]
    others = [raw.hex(" ").upper() for raw in before if raw not in ended]
    if others:
        evidence.rests_on("cia", ABORT_NAMES_ITS_TRANSFER)
    assert not others, (f"{what}: before the answer to the upload of 1000h the device sent {others}"
                        + (f" (an abort of the open transfer names {open_key[0]:04X}h.{open_key[1]:02X})"
                           if open_key else " (no transfer was open)"))
    for raw in ended:
        evidence.note(f"{what}: the device aborted the open transfer first ({SdoResponse(raw).describe()}), "
                      f"allowed by {ABORT_NAMES_ITS_TRANSFER}")
    if response is None and ended:
        evidence.note(f"{what}: the upload of 1000h was taken as a wrong frame of the open transfer (no answer to "
                      "it); sent again")
        response = sdo.request(request)
    assert response is not None, f"{what}: no answer to the upload of 1000h"
    assert echoes(request, response.raw), f"{what}: the answer {response.describe()} does not echo 1000h.00"
    if response.is_abort:
        evidence.inferred_problem(f"{what}: the upload of 1000h was refused ({abort_name(response.abort_code or 0)})",
                                  "CiA 301 leaves open what a server does with a transfer left open; we expect it "
                                  "to serve the next initiate request")


def request_mux(key: tuple[int, int]) -> bytes:
    """Bytes 1-3 of a frame about ``key``: index (little-endian) and sub-index."""
    return upload_request(*key)[1:4]


@pytest.mark.requires("segmented_sdo")
def test_new_request_while_segmented_transfer_open(dut, sdo, evidence):
    """An initiate request in the middle of a segmented upload is answered (served, or refused with an abort
    that echoes it), where the device may abort the open transfer first, or take the request as a wrong frame of
    it and serve it sent again; after a client abort the device serves requests as before."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.6 (every initiate request is confirmed), §7.2.4.3.17")
    key = _open_upload(dut, sdo)
    _next_initiate_served(dut, sdo, evidence, "new request during a segmented upload", open_key=key)
    sdo.abort(*key, SdoAbortCode.GENERAL_ERROR)
    assert dut.responds(), "the device stopped answering after a new request during a segmented upload"


@pytest.mark.requires("segmented_sdo")
def test_client_abort_ends_segmented_transfer(dut, sdo, evidence):
    """An abort from the client mid-transfer is not answered and ends the transfer: a further segment request
    is refused (05040001h), not served, and the next upload is served."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.17 (abort SDO transfer: unconfirmed, ends the transfer)")
    key = _open_upload(dut, sdo)
    answers = sdo.abort_unanswered(*key, SdoAbortCode.GENERAL_ERROR)
    assert not answers, f"the client's abort was answered: {[a.hex(' ') for a in answers]}"
    response = sdo.upload_segment(toggle=1)
    judge_refusal(dut, response, {SdoAbortCode.COMMAND_SPECIFIER}, {SdoAbortCode.GENERAL_ERROR},
                  "upload segment request after the client's abort", evidence)
    _next_initiate_served(dut, sdo, evidence, "after the client's abort")


@pytest.mark.requires("segmented_sdo")
def test_transfer_left_open_does_not_block_the_server(dut, sdo, evidence):
    """A segmented upload left half-finished: whatever the device does with it (a timeout abort 05040000h naming
    its entry, or nothing; at the next request an abort naming it), it serves the next initiate request."""
    evidence.rests_on("inferred", "CiA 301 leaves open what a server does with a transfer left open; §7.2.4.3.17 "
                                  "05040000h (SDO protocol timed out)")
    key = _open_upload(dut, sdo)
    mark = dut.frames.mark()
    ended = False
    for raw in sdo.silent_after(mark):
        if raw[0] != SDO_ABORT or raw[1:4] != request_mux(key):
            evidence.rests_on("cia", ABORT_NAMES_ITS_TRANSFER)
        assert raw[0] == SDO_ABORT, f"a frame after the transfer was left open, not an abort: {raw.hex(' ').upper()}"
        assert raw[1:4] == request_mux(key), (f"an abort of the transfer left open ({key[0]:04X}h.{key[1]:02X}) "
                                              f"names another entry: {raw.hex(' ').upper()}")
        ended = True
        evidence.note(f"the device ended the transfer by itself: {SdoResponse(raw).describe()}")
    _next_initiate_served(dut, sdo, evidence, "after a transfer left open", open_key=None if ended else key)
    sdo.abort(*key, SdoAbortCode.TIMEOUT)
