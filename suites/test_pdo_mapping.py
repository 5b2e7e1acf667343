"""TPDO mapping (CiA 301 §7.5.2.38; CTT PDO 21-33): the default mapping, the mapping procedure, its errors,
dummy entries and fixed mappings.

A variable mapping changes only in the CiA 301 procedure: COB-ID bit 31 set, sub 0 = 0, the entries,
sub 0 = n, bit 31 cleared. Every test that changes a mapping holds it in a ``MappingCustody``
(``dut/tpdo/pdo_mapping.py``), which puts the COB-ID and the mapping back in that order, also when the test
fails (after Ctrl-C the run's restore does it from its snapshot). After each refused write the mapping
is read back: it must be unchanged. The equality of each 1A0xh entry with the profile's default is
test_object_dictionary's (factory defaults); here the default mapping is checked against the objects
it names.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import pytest

from encoder_conformance.cia.cia301 import (
    COB_ID_INVALID,
    DUMMY_BITS,
    PDO_MAPPING_OFFSET,
    PDO_MAX_BITS,
    SdoAbortCode,
    cob_id_valid,
    mapping_word,
)
from encoder_conformance.coverage import Hold
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link import format_frames
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.dut.tpdo import (
    Entry,
    MappingCustody,
    NoUsableTpdo,
    TpdoUnderTest,
    apply_mapping,
    describe,
    invalidate,
    read_mapping,
)
from encoder_conformance.plugin.evidence import Evidence
from encoder_conformance.plugin.skips import not_applicable, not_judged, skip_text
from encoder_conformance.plugin.suite_helpers import assert_abort, documented_quirk, expected_aborts
from encoder_conformance.profile import datatypes
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("CiA 301 §7.5.2.38 (TPDO mapping)"), pytest.mark.requires("tpdos")]

PROCEDURE = "CiA 301 §7.5.2.38 (mapping changed only with the PDO invalid and sub 0 = 0; CTT PDO 22-24)"
ENTRY_RULE = "CiA 301 §7.5.2.38 (a mapped object must exist and be mappable; CTT PDO 25-32)"
POSITION = 0x6004


def _mapping_objects(dut: DeviceUnderTest) -> list[int]:
    return sorted(i for i in dut.profile.objects if 0x1A00 <= i <= 0x1BFF)


def _object_bits(dut: DeviceUnderTest, index: int, sub: int) -> int | None:
    entry = dut.profile.entry(index, sub)
    size = None if entry is None else datatypes.size_bytes(entry.type)
    return None if size is None else 8 * size


@dataclass
class VariableMapping:
    """A TPDO whose COB-ID, sub 0 and entries the profile lets write."""

    comm: int
    slots: int  # writable entries (sub 1..)

    @property
    def mapping(self) -> int:
        return self.comm + PDO_MAPPING_OFFSET


def _variable(dut: DeviceUnderTest, comm: int) -> VariableMapping | None:
    mapping = dut.profile.objects.get(comm + PDO_MAPPING_OFFSET)
    cob = dut.profile.entry(comm, 1)
    if mapping is None or cob is None or not cob.writable:
        return None
    entries = mapping.entries()
    slots = 0
    while slots + 1 in entries and entries[slots + 1].writable:
        slots += 1
    return VariableMapping(comm, slots) if 0 in entries and entries[0].writable and slots else None


def _first_variable(dut: DeviceUnderTest, slots: int = 1) -> VariableMapping:
    for mapping in _mapping_objects(dut):
        found = _variable(dut, mapping - 0x200)
        if found is not None and found.slots >= slots:
            return found
    fixed = "" if _mapping_objects(dut) else " (the profile has no mapping objects)"
    not_applicable(f"no TPDO with a writable COB-ID, sub 0 and {slots} writable mapping entries{fixed}")


def _mappable(dut: DeviceUnderTest) -> list[Entry]:
    """Readable PDO-mappable objects of at most 32 bits, by index."""
    found = []
    for index, sub, _, entry in dut.profile.iter_entries():
        bits = _object_bits(dut, index, sub)
        if entry.pdo_mappable and entry.readable and bits is not None and bits <= 32:
            found.append((index, sub, bits))
    return found


def _plan(dut: DeviceUnderTest, slots: int) -> list[Entry]:
    """A new mapping: up to two other mappable objects, then the position (so that it sits at an offset)."""
    candidates = _mappable(dut)
    position = [c for c in candidates if c[0] == POSITION and c[1] == 0][:1]
    room = PDO_MAX_BITS - sum(c[2] for c in position)
    plan: list[Entry] = []
    for candidate in (c for c in candidates if c not in position):
        if len(plan) < min(2, slots - len(position)) and candidate[2] <= room:
            plan.append(candidate)
            room -= candidate[2]
    return (plan + position) or candidates[:1]


@pytest.fixture
def variable_tpdo(dut: DeviceUnderTest) -> Iterator[tuple[VariableMapping, MappingCustody]]:
    """The first TPDO with a variable mapping, its COB-ID and mapping in custody (back in pre-operational first)."""
    found = _first_variable(dut)
    with MappingCustody(dut, found.comm) as custody:
        yield found, custody
        if dut.usable:
            dut.nmt.back_to_preoperational()


def _write(dut: DeviceUnderTest, index: int, sub: int, value: int, size: int) -> sdo_frames.SdoResponse:
    return dut.expect_abort(sdo_frames.expedited_download_request(index, sub, value.to_bytes(size, "little")))


def _unchanged(dut: DeviceUnderTest, tpdo: VariableMapping, before: list[Entry], what: str) -> None:
    after = read_mapping(dut, tpdo.comm)
    assert after == before, (f"{what}: the mapping of {tpdo.mapping:04X}h reads {describe(after)}, "
                             f"was {describe(before)}")


# -- the default mapping -----------------------------------------------------------------------------------

def test_default_mapping_names_mappable_objects(dut: DeviceUnderTest, evidence: Evidence) -> None:
    """Each TPDO's mapping as found names existing, PDO-mappable objects with their own length, 64 bits at most
    in all (CiA 301 §7.5.2.38; CTT PDO 21)."""
    objects = _mapping_objects(dut)
    if not objects:
        found = dut.profile.quirk(fx.FixedTpdoMapping)
        reason = f" (fixed payload, quirk {found.id})" if found else ""
        not_applicable(f"the profile has no TPDO mapping objects{reason}")
    lengths = dut.profile.quirk(fx.MappingLengthDiffers)
    problems = []
    for mapping in objects:
        entries = read_mapping(dut, mapping - 0x200)
        evidence.note(f"{mapping:04X}h = {describe(entries)}")
        for sub, (index, obj_sub, bits) in enumerate(entries, start=1):
            entry = dut.profile.entry(index, obj_sub)
            label = f"{mapping:04X}h.{sub:02X} = {mapping_word(index, obj_sub, bits):08X}h"
            if entry is None:
                problems.append(f"{label}: {index:04X}h.{obj_sub:02X} is not in the profile")
                continue
            if not entry.pdo_mappable:
                problems.append(f"{label}: {index:04X}h.{obj_sub:02X} is not PDO-mappable in the profile")
            size = _object_bits(dut, index, obj_sub)
            if size != bits:
                documented = lengths is not None and lengths.params.entry == (mapping, sub) and (
                    lengths.params.mapping == mapping_word(index, obj_sub, bits))
                if documented and lengths is not None:
                    evidence.deviation(lengths.id, lengths.quirk.title)
                else:
                    problems.append(f"{label}: maps {bits} bits, {index:04X}h.{obj_sub:02X} is {entry.type} "
                                    f"({size} bits)")
        total = sum(bits for _, _, bits in entries)
        if total > PDO_MAX_BITS:
            problems.append(f"{mapping:04X}h maps {total} bits (at most {PDO_MAX_BITS})")
    evidence.rests_on("cia", "CiA 301 §7.5.2.38 (mapping entries: index, sub-index, the object's length; 64 bits)")
    assert not problems, "default TPDO mapping:\n" + "\n".join(problems)


# -- the procedure and the payload ---------------------------------------------------------------------------

@pytest.mark.usefixtures("no_error_left")  # NMT start: no error may hold the device out of operational
def test_mapping_procedure_payload_matches_sdo(dut: DeviceUnderTest, settings_journal, shaft,
                                               evidence: Evidence) -> None:
    """A new mapping written by the CiA 301 procedure is accepted and the TPDO carries the mapped objects in
    that order, each equal to its SDO value read before and after (shaft at rest) (CiA 301 §7.5.2.38, §7.2.2;
    CTT PDO 22)."""
    try:
        choice = dut.tpdo.choose(1, [1])
    except NoUsableTpdo as exc:
        skip_text(str(exc), exc.hold)
    tpdo = _variable(dut, choice.comm)
    if tpdo is None:
        fixed = "is fixed (sub 0 or entries read-only)" if _mapping_objects(dut) else "has no object"
        not_applicable(f"the mapping of {choice.comm:04X}h {fixed}")
    plan = _plan(dut, tpdo.slots)
    if not plan:
        not_applicable("the profile names no readable PDO-mappable object of at most 32 bits")
    if shaft is not None:
        shaft.turn_by(0.37)  # a position other than 0, which a shifted entry's zeros would match
    evidence.rests_on("cia", "CiA 301 §7.5.2.38 (procedure), §7.2.2 (a PDO carries the mapped objects in order)")
    sent = TpdoUnderTest(dut, settings_journal, tpdo.comm, choice.transmission_type)
    with MappingCustody(dut, tpdo.comm):
        sent.configure(trans_type=sent.trans_type)
        apply_mapping(dut, tpdo.comm, plan)
        assert read_mapping(dut, tpdo.comm) == plan, f"{tpdo.mapping:04X}h does not read back {describe(plan)}"
        evidence.note(f"{tpdo.mapping:04X}h = {describe(plan)}, {tpdo.comm:04X}h.02 = {choice.transmission_type}")
        cob_id = sent.can_id()
        try:
            before = [dut.read(i, s)[: b // 8] for i, s, b in plan]
            dut.nmt.transition("operational", settings_journal, evidence)
            mark = dut.frames.mark()
            for _ in range(choice.transmission_type):
                dut.send_sync()
            window = 2 * dut.sdo_timeout + sent.answer_s  # a TPDO the SYNCs owe: the wait ends when it comes
            frame = dut.frames.wait_for(sent.frames(cob_id), window, mark)
            after = [dut.read(i, s)[: b // 8] for i, s, b in plan]
        finally:
            if dut.usable:
                dut.nmt.back_to_preoperational()
    assert frame is not None, f"no TPDO {cob_id:03X}h after SYNC\n{format_frames(dut.frames.since(mark)[:10])}"
    data, offset, problems, judged = bytes(frame.data), 0, [], 0
    evidence.note(f"TPDO {format_frames([frame])}")
    if len(data) != sum(b for _, _, b in plan) // 8:
        problems.append(f"DLC {len(data)}, the mapping has {sum(b for _, _, b in plan) // 8} bytes")
    for (index, sub, bits), first, last in zip(plan, before, after, strict=True):
        carried = data[offset:offset + bits // 8]
        offset += bits // 8
        if first != last:
            evidence.note(f"{index:04X}h.{sub:02X} changed between the SDO reads: not judged")
            continue
        judged += 1
        if carried != first:
            problems.append(f"{index:04X}h.{sub:02X} at byte {offset - bits // 8}: TPDO {carried.hex(' ').upper()}, "
                            f"SDO {first.hex(' ').upper()}")
    assert not problems, f"TPDO {cob_id:03X}h with {describe(plan)}:\n" + "\n".join(problems)
    if not judged:
        not_judged(Hold.VALUES_CHANGED, f"every mapped object ({describe(plan)}) changed between the SDO reads before "
                                        "and after the TPDO: nothing to compare its payload with (CiA 301 §7.2.2)")


# -- errors ------------------------------------------------------------------------------------------------

def _opened(dut: DeviceUnderTest, tpdo: VariableMapping) -> list[Entry]:
    """Steps 1 and 2 of the procedure (PDO invalid, sub 0 = 0); the entries mapped before."""
    before = read_mapping(dut, tpdo.comm)
    invalidate(dut, tpdo.comm)
    dut.write_uint(tpdo.mapping, 0, 0, 1)
    return before


def _raw_entries(dut: DeviceUnderTest, tpdo: VariableMapping) -> list[int]:
    return [dut.read_uint(tpdo.mapping, sub) for sub in range(1, tpdo.slots + 1)]


def test_mapping_of_missing_object_refused(dut: DeviceUnderTest, variable_tpdo, evidence: Evidence) -> None:
    """An entry naming an object the device does not have is refused with 06020000h, the entry unchanged
    (CiA 301 §7.5.2.38; CTT PDO 25/26)."""
    tpdo, _ = variable_tpdo
    index = next(i for i in range(0x6FFF, 0x6000, -1) if i not in dut.profile.objects)
    _opened(dut, tpdo)
    entries = _raw_entries(dut, tpdo)
    response = _write(dut, tpdo.mapping, 1, mapping_word(index, 0, 32), 4)
    evidence.rests_on("cia", ENTRY_RULE)
    assert_abort(dut, response, expected_aborts(dut, "no_object", evidence),
                 f"{tpdo.mapping:04X}h.01 = {index:04X}0020h")
    assert _raw_entries(dut, tpdo) == entries, "the refused entry changed the mapping"


def test_mapping_of_unmappable_object_refused(dut: DeviceUnderTest, variable_tpdo, evidence: Evidence) -> None:
    """An entry naming an existing object that is not PDO-mappable is refused with 06040041h, the entry
    unchanged (CiA 301 §7.5.2.38; CTT PDO 27-32)."""
    tpdo, _ = variable_tpdo
    target = next(((i, s, b) for i, s, _, e in dut.profile.iter_entries() if not e.pdo_mappable and e.readable
                   and i >= 0x1000 and (b := _object_bits(dut, i, s)) and b <= 32), None)
    if target is None:
        not_applicable("every object of the profile is PDO-mappable")
    _opened(dut, tpdo)
    entries = _raw_entries(dut, tpdo)
    response = _write(dut, tpdo.mapping, 1, mapping_word(*target), 4)
    evidence.rests_on("cia", ENTRY_RULE)
    assert_abort(dut, response, {SdoAbortCode.NOT_MAPPABLE}, f"{tpdo.mapping:04X}h.01 = {mapping_word(*target):08X}h")
    assert _raw_entries(dut, tpdo) == entries, "the refused entry changed the mapping"


def test_mapping_longer_than_64_bits_refused(dut: DeviceUnderTest, evidence: Evidence) -> None:
    """Entries of more than 64 bits in all are refused with 06040042h, at the entry or at sub 0 = n, and
    the mapping stays disabled (CiA 301 §7.5.2.38; CTT PDO 25/26)."""
    tpdo = _first_variable(dut, slots=2)
    widest = max(_mappable(dut), key=lambda c: c[2], default=None)
    if widest is None or widest[2] * tpdo.slots <= PDO_MAX_BITS:
        not_applicable(f"{tpdo.slots} entries of mappable objects cannot exceed {PDO_MAX_BITS} bits")
    count = PDO_MAX_BITS // widest[2] + 1
    evidence.rests_on("cia", "CiA 301 §7.5.2.38 (06040042h: the mapped objects exceed the PDO length)")
    with MappingCustody(dut, tpdo.comm):
        _opened(dut, tpdo)
        response = None
        for sub in range(1, count + 1):
            response = _write(dut, tpdo.mapping, sub, mapping_word(*widest), 4)
            if response.is_abort:
                break
        what = f"{count} x {mapping_word(*widest):08X}h ({count * widest[2]} bits)"
        if response is not None and not response.is_abort:
            response = _write(dut, tpdo.mapping, 0, count, 1)
            what += f", sub 0 = {count}"
        evidence.note(f"{tpdo.mapping:04X}h: {what}: {response.describe() if response else 'nothing written'}")
        assert response is not None
        assert_abort(dut, response, {SdoAbortCode.PDO_TOO_LONG}, f"{tpdo.mapping:04X}h: {what}")
        assert dut.read_uint(tpdo.mapping, 0) == 0, f"{tpdo.mapping:04X}h sub 0 is not 0 after the refused mapping"


def test_mapping_entry_refused_while_sub0_not_zero(dut: DeviceUnderTest, variable_tpdo, evidence: Evidence) -> None:
    """With the PDO invalid but sub 0 = n (mapping enabled), an entry write is refused and the mapping stays
    (CiA 301 §7.5.2.38 step 2; CTT PDO 23/24). CiA 301 names no code: the code is recorded, not judged."""
    tpdo, _ = variable_tpdo
    before = read_mapping(dut, tpdo.comm)
    if not before:
        not_applicable(f"{tpdo.mapping:04X}h maps nothing (sub 0 = 0)")
    invalidate(dut, tpdo.comm)
    other = next((c for c in _mappable(dut) if c != before[0]), before[0])
    response = _write(dut, tpdo.mapping, 1, mapping_word(*other), 4)
    evidence.rests_on("cia", PROCEDURE)
    evidence.note(f"{tpdo.mapping:04X}h.01 = {mapping_word(*other):08X}h with sub 0 = {len(before)}: "
                  f"{response.describe()}")
    assert response.is_abort, (f"{tpdo.mapping:04X}h.01 written while sub 0 = {len(before)}: accepted "
                               "(the procedure needs sub 0 = 0 first)")
    _unchanged(dut, tpdo, before, "entry written while sub 0 was not 0")


def test_mapping_refused_while_pdo_valid(dut: DeviceUnderTest, variable_tpdo, evidence: Evidence) -> None:
    """With the PDO valid (COB-ID bit 31 clear), sub 0 = 0 is refused and the mapping stays (CiA 301 §7.5.2.38
    step 1; CTT PDO 23/24). CiA 301 names no code: the code is recorded, not judged."""
    found = dut.profile.quirk(fx.MappingChangeWhileValid)
    if found is not None:
        evidence.deviation(found.id, found.quirk.title)
        not_applicable(f"the manual's procedure changes the mapping with the PDO valid (quirk "
                    f"{found.id}; test_documented_procedure_with_pdo_valid checks it)")
    tpdo, _ = variable_tpdo
    before = read_mapping(dut, tpdo.comm)
    _make_valid(dut, tpdo, before, evidence)
    response = _write(dut, tpdo.mapping, 0, 0, 1)
    evidence.rests_on("cia", PROCEDURE)
    evidence.note(f"{tpdo.mapping:04X}h.00 = 0 with the PDO valid: {response.describe()}")
    assert response.is_abort, f"{tpdo.mapping:04X}h.00 = 0 written while {tpdo.comm:04X}h is valid: accepted"
    _unchanged(dut, tpdo, before, "sub 0 written while the PDO was valid")


def _make_valid(dut: DeviceUnderTest, tpdo: VariableMapping, before: list[Entry], evidence: Evidence) -> None:
    """Clear COB-ID bit 31 where the PDO is invalid (the custody puts it back); skips if it maps nothing."""
    cob_id = dut.read_uint(tpdo.comm, 1)
    if cob_id & COB_ID_INVALID:
        if not before:
            not_applicable(f"{tpdo.comm:04X}h is invalid and maps nothing")
        dut.write_uint(tpdo.comm, 1, cob_id_valid(cob_id), 4)
        evidence.note(f"{tpdo.comm:04X}h.01 bit 31 cleared (PDO valid) for the test")


def test_documented_procedure_with_pdo_valid(dut: DeviceUnderTest, variable_tpdo, evidence: Evidence) -> None:
    """Documented quirk: the manual's procedure (sub 0 = 0, the entries, sub 0 = n) changes the mapping while the
    PDO stays valid; every step is accepted and the mapping reads as written."""
    params = documented_quirk(dut, fx.MappingChangeWhileValid, evidence,
                              "the CiA 301 procedure makes the PDO invalid first")
    tpdo, _ = variable_tpdo
    before = read_mapping(dut, tpdo.comm)
    _make_valid(dut, tpdo, before, evidence)
    plan = _plan(dut, tpdo.slots)
    steps = [(0, 0, 1), *((sub, mapping_word(*entry), 4) for sub, entry in enumerate(plan, start=1)),
             (0, len(plan), 1)]
    refused = []
    for sub, value, size in steps:
        response = _write(dut, tpdo.mapping, sub, value, size)
        if response.is_abort:
            refused.append(f"{tpdo.mapping:04X}h.{sub:02X} = {value:0{2 * size}X}h: {response.describe()}")
    evidence.rests_on("manual", f"{params.procedure}")
    evidence.note(f"{tpdo.mapping:04X}h with {tpdo.comm:04X}h valid: {describe(before)} -> {describe(plan)}")
    assert not refused, "the documented procedure with the PDO valid was refused:\n" + "\n".join(refused)
    after = read_mapping(dut, tpdo.comm)
    assert after == plan, f"{tpdo.mapping:04X}h reads {describe(after)} after the procedure, written {describe(plan)}"


# -- dummy entries and fixed mappings ---------------------------------------------------------------------

@pytest.mark.usefixtures("no_error_left")  # NMT start: no error may hold the device out of operational
def test_dummy_mapping(dut: DeviceUnderTest, settings_journal, shaft, evidence: Evidence) -> None:
    """Where the profile declares dummy mapping (capabilities.pdo_dummy_mapping, EDS [DummyUsage]), a dummy entry
    is accepted and takes its data type's bytes in the TPDO: the next object follows it (CiA 301 §7.4.7.1,
    §7.5.2.38; CTT PDO 33). The dummy's own bytes are not judged."""
    dummies = dut.profile.capabilities.pdo_dummy_mapping
    if not dummies:
        not_applicable("the profile declares no dummy mapping (capabilities.pdo_dummy_mapping)")
    try:
        choice = dut.tpdo.choose(1, [1])
    except NoUsableTpdo as exc:
        skip_text(str(exc), exc.hold)
    tpdo = _variable(dut, choice.comm)
    objects = [c for c in _mappable(dut) if c[2] <= 32]
    if tpdo is None or tpdo.slots < 2 or not objects:
        not_applicable("no TPDO with two writable mapping entries and a mappable object")
    dummy = max(dummies, key=lambda d: (DUMMY_BITS[d] % 8 == 0, DUMMY_BITS[d]))
    target = next((c for c in objects if c[0] == POSITION), objects[0])
    plan = [(dummy, 0, DUMMY_BITS[dummy]), target]
    if shaft is not None:
        shaft.turn_by(0.37)  # a position other than 0, which a dummy's zeros would match
    evidence.rests_on("cia", "CiA 301 §7.4.7.1 (dummy mapping), §7.5.2.38")
    sent = TpdoUnderTest(dut, settings_journal, tpdo.comm, choice.transmission_type)
    with MappingCustody(dut, tpdo.comm):
        sent.configure(trans_type=sent.trans_type)
        apply_mapping(dut, tpdo.comm, plan)
        cob_id = sent.can_id()
        try:
            expected = dut.read(target[0], target[1])[: target[2] // 8]
            dut.nmt.transition("operational", settings_journal, evidence)
            mark = dut.frames.mark()
            for _ in range(choice.transmission_type):
                dut.send_sync()
            frame = dut.frames.wait_for(sent.frames(cob_id), 2 * dut.sdo_timeout, mark)
            again = dut.read(target[0], target[1])[: target[2] // 8]
        finally:
            if dut.usable:
                dut.nmt.back_to_preoperational()
    assert frame is not None, f"no TPDO {cob_id:03X}h after SYNC with {describe(plan)}"
    start = DUMMY_BITS[dummy] // 8
    carried = bytes(frame.data)[start:start + target[2] // 8]
    evidence.note(f"{describe(plan)}: {format_frames([frame])}")
    if expected != again:
        not_judged(Hold.VALUES_CHANGED, f"{target[0]:04X}h changed between the SDO reads")
    assert carried == expected, (f"{describe(plan)}: bytes {start}.. carry {carried.hex(' ').upper()}, "
                                 f"{target[0]:04X}h reads {expected.hex(' ').upper()}")


def test_fixed_mapping_refuses_changes(dut: DeviceUnderTest, evidence: Evidence) -> None:
    """A fixed mapping refuses changes as documented: read-only mapping entries abort 06010002h, a device without
    mapping objects 06020000h; the mapping stays (CiA 301 §7.2.4.3.17, §7.5.2.38; the manual's object table)."""
    objects = _mapping_objects(dut)
    if not objects:
        found = dut.profile.quirk(fx.FixedTpdoMapping)
        if found is None:
            not_applicable("the profile has no mapping objects and documents no fixed payload")
        evidence.deviation(found.id, found.quirk.title)
        evidence.rests_on("manual", f"{found.quirk.manual} (quirk {found.id}: no 1A00h)")
        response = _write(dut, 0x1A00, 0, 0, 1)
        assert_abort(dut, response, expected_aborts(dut, "no_object", evidence), "1A00h.00 = 0 (no mapping object)")
        return
    fixed = [(m, s, e) for m in objects for s, e in dut.profile.objects[m].entries().items() if not e.writable]
    if not fixed:
        not_applicable("every mapping entry is writable (variable mapping)")
    evidence.rests_on("manual", f"{dut.profile.objects[fixed[0][0]].manual} (mapping read-only); CiA 301 §7.2.4.3.17")
    problems = []
    for mapping, sub, _ in fixed:
        before = dut.read(mapping, sub)
        value = 0 if sub == 0 else mapping_word(POSITION, 0, 8)
        response = _write(dut, mapping, sub, value, len(before))
        try:
            assert_abort(dut, response, expected_aborts(dut, "write_ro", evidence),
                         f"{mapping:04X}h.{sub:02X} = {value:X}h")
        except AssertionError as exc:
            problems.append(str(exc).splitlines()[0])
        after = dut.read(mapping, sub)
        if after != before:
            problems.append(f"{mapping:04X}h.{sub:02X} reads {after.hex(' ').upper()} after the write, was "
                            f"{before.hex(' ').upper()}")
            dut.write(mapping, sub, before)  # best effort; the run's restore checks it
    assert not problems, "fixed mapping:\n" + "\n".join(problems)
