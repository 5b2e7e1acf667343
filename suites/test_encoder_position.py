"""The encoder's position function (CiA 406 6000h-6004h, 6030h, 6500h, 6509h) against the reference model.

Every expectation comes from ``encoder_conformance.models.encoder`` fed with the settings read from
the device, so what the twin computes and what the suite expects are one definition. The preset
moves the position where a check needs it (any bench); checks of counting direction, scaling,
the wrap and speed need real rotation and skip on a bench without a shaft drive. Settings, the
reference point (by presetting) and the shaft are put back after each test (fixture ``encoder``).
"""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import COB_ID_INVALID, PDO_MAPPING_OFFSET, can_id_of, cob_id_valid
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.custody import ReferenceCustody
from encoder_conformance.dut.link import format_frames
from encoder_conformance.dut.store import AUTO_STORED
from encoder_conformance.dut.tpdo import TpdoUnderTest
from encoder_conformance.models.encoder import objects as od
from encoder_conformance.models.encoder.position import position_limits, units_per_rev, unsigned_in_span
from encoder_conformance.plugin.options import settings_of
from encoder_conformance.plugin.skips import not_applicable, not_equipped
from encoder_conformance.plugin.suite_helpers import documented_quirk
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("CiA 406 §6 (6000h-6004h, 6500h, 6509h)"), pytest.mark.requires("encoder")]

#: units the direction and wrap checks turn the shaft by
STEP_UNITS = 10
#: how long a device may integrate its speed value before it shows a new shaft speed (WDGA 2105h sub 2:
#: 1000 ms by default); our inference for devices that do not say
SPEED_SETTLE_S = 2.5


def _signed_distance(before: int, after: int, span: int) -> int:
    """The shortest way from ``before`` to ``after`` on a range that wraps at ``span``."""
    distance = unsigned_in_span(after - before, span)
    return distance - span if distance > span // 2 else distance


def _rotation(encoder):
    """The shaft drive; skips the test where the bench has none (it needs real rotation)."""
    if encoder.shaft is None:
        not_equipped(f"needs real rotation: {encoder.why_no_shaft}")
    return encoder.shaft


def _allow_preset(encoder) -> None:
    """Where the preset is writable only with the scaling bit set (quirk writes_need_scaling_bit), set it for the
    whole test (the access layer would otherwise switch it on and off around every preset)."""
    bit = encoder.access.scaling_bit_needed_for_preset()
    if bit is not None:
        operating = encoder.access.objects.operating
        encoder.write(operating, 0, (encoder.access.read_int(operating) or 0) | bit)


def _set_code_sequence(encoder, ccw: bool) -> None:
    operating_index = encoder.access.objects.operating
    operating = encoder.access.read_int(operating_index) or 0
    wanted = operating | 1 if ccw else operating & ~1
    if wanted != operating:
        encoder.write(operating_index, 0, wanted)


def _rests_on_preset_clause(encoder, evidence) -> None:
    if encoder.access.objects.relocated:
        evidence.rests_on("manual", f"the manual's preset object {encoder.access.objects.preset:04X}h "
                                    "(quirk manufacturer_encoder_objects)")
    else:
        evidence.rests_on("cia", "CiA 406 6003h (preset value) and 6509h (offset value)")


def _preset_stores_itself(encoder) -> bool:
    """Whether a preset changes what the device stores (its preset object persists itself): then presetting is
    destructive under the custody rules, else the run gives the reference point back by presetting again."""
    custody = ReferenceCustody(encoder.access.dut)
    return custody.store_may_have_changed({AUTO_STORED: 1}, history_unknown=False)


def test_position_plausible_and_moving(encoder, evidence):
    """The position lies in the measuring range, follows the shaft where the bench turns it, and reads a preset
    value at once where presetting changes nothing stored (the acceptance check of the encoder function)."""
    _rests_on_preset_clause(encoder, evidence)
    access = encoder.access
    settings = access.settings(functions=False)
    low, high = settings.limits()
    before = access.position()
    evidence.note(f"position {before}, range {low} .. {high}")
    assert low <= before <= high, f"the position reads {before}, outside the measuring range {low} .. {high}"
    checked = []
    if encoder.shaft is not None:
        per_rev = units_per_rev(settings.geometry, settings.scaling)
        encoder.shaft.turn_by(STEP_UNITS / per_rev)
        turned = access.position()
        evidence.note(f"{STEP_UNITS} units clockwise: {before} -> {turned}")
        assert turned != before, f"the shaft turned by {STEP_UNITS} units but the position still reads {before}"
        checked.append("shaft")
    caps = access.dut.profile.capabilities
    if caps.preset and not _preset_stores_itself(encoder):
        _allow_preset(encoder)
        now = access.position()
        target = settings.shown(unsigned_in_span(now + settings.span // 3, settings.span))
        reached = encoder.preset(target)
        evidence.note(f"preset {target}: {now} -> {reached} (the reference point is put back by presetting)")
        assert reached == target, f"preset {target}: the position reads {reached} (it read {now} before)"
        checked.append("preset")
    elif caps.preset:
        evidence.note("no preset: the preset object stores itself (persisted_by auto), so a preset would change "
                      "what the device remembers")
    if not checked:
        evidence.note("the position could not be moved: no shaft drive and no preset that leaves the memory alone")


@pytest.mark.destructive
@pytest.mark.requires("preset")
@pytest.mark.parametrize("ccw", [False, True], ids=["cw", "ccw"])
@pytest.mark.parametrize("where", ["zero", "middle", "top", "bottom"])
def test_preset_sets_position_and_offset(encoder, evidence, where: str, ccw: bool):
    """Writing the preset makes the position read it at once, and 6509h becomes preset minus the position
    before it (modulo the range): at zero, mid-range and both range edges, in both code sequences."""
    _rests_on_preset_clause(encoder, evidence)
    _allow_preset(encoder)
    _set_code_sequence(encoder, ccw)
    access = encoder.access
    settings = access.settings(functions=False)
    low, high = position_limits(settings.span, settings.signed)
    target = {"zero": 0, "middle": settings.shown(settings.span // 3), "top": high, "bottom": low}[where]
    if where == "bottom" and low == 0:
        not_applicable("the range starts at 0 (the 'zero' case)")
    if access.position() == target:  # already there: move away first, or a preset that does nothing would pass
        away = settings.shown(unsigned_in_span(target + settings.span // 7, settings.span))
        moved = encoder.preset(away)
        assert moved == away, f"preset {away}: the position reads {moved} (it read {target} before)"
    before, offset_before = access.position(), access.offset()
    reached = encoder.preset(target)
    evidence.note(f"span {settings.span}, code sequence {'CCW' if ccw else 'CW'}: position {before} -> preset "
                  f"{target} -> {reached}")
    assert reached == target, f"preset {target}: the position reads {reached} (it read {before} before)"
    if offset_before is None:
        if access.dut.profile.has_effect(fx.OffsetIsZeroingPoint):
            documented_quirk(access.dut, fx.OffsetIsZeroingPoint, evidence, "6509h = preset - position")
        return
    unshifted = unsigned_in_span(before - offset_before, settings.span)
    expected = unsigned_in_span(target - unshifted, settings.span)
    offset = access.offset()
    assert offset is not None, "6509h could not be read after the preset"
    assert unsigned_in_span(offset - expected, settings.span) == 0, (
        f"6509h = {offset} after preset {target}; the position was {before} with offset {offset_before}, so "
        f"the offset must be {expected} (modulo {settings.span})")


@pytest.mark.destructive
@pytest.mark.requires("preset")
def test_preset_is_kept_while_the_shaft_turns(encoder, evidence):
    """After a preset the position follows the shaft from the preset value (the offset is applied, not a one-off)."""
    _rests_on_preset_clause(encoder, evidence)
    shaft = _rotation(encoder)
    _allow_preset(encoder)
    settings = encoder.access.settings(functions=False)
    target = settings.shown(settings.span // 2)
    encoder.preset(target)
    per_rev = units_per_rev(settings.geometry, settings.scaling)
    shaft.turn_by(STEP_UNITS / per_rev * (-1 if settings.scaling.ccw else 1))
    observed = encoder.access.position()
    expected = settings.shown(unsigned_in_span(target + STEP_UNITS, settings.span))
    assert observed == expected, (
        f"preset {target}, then {STEP_UNITS} units counting up: the position reads {observed}, the model {expected}")


@pytest.mark.destructive
@pytest.mark.requires("preset")
def test_position_wraps_at_the_total_measuring_range(encoder, evidence):
    """Counting up across the end of the range continues at its start (multi-turn wrap at TMR; singleturn at
    one revolution): preset just below the end, turn a few units up, compare with the model."""
    _rests_on_preset_clause(encoder, evidence)
    shaft = _rotation(encoder)
    _allow_preset(encoder)
    settings = encoder.access.settings(functions=False)
    low, high = settings.limits()
    start = settings.shown(unsigned_in_span(high - 1, settings.span))
    encoder.preset(start)
    per_rev = units_per_rev(settings.geometry, settings.scaling)
    shaft.turn_by(4 / per_rev * (-1 if settings.scaling.ccw else 1))
    observed = encoder.access.position()
    expected = settings.shown(unsigned_in_span(start + 4, settings.span))
    evidence.note(f"range {low} .. {high}: preset {start}, 4 units up -> {observed}")
    assert observed == expected, (
        f"from {start} four units up must wrap to {expected} (range {low} .. {high}); observed {observed}")


@pytest.mark.destructive
def test_code_sequence_sets_the_counting_direction(encoder, evidence):
    """6000h bit 0: turning the shaft clockwise counts up with bit 0 = 0 and down with bit 0 = 1."""
    objects = encoder.access.objects
    if objects.relocated:
        evidence.rests_on("manual", f"code sequence bit 0 of {objects.operating:04X}h (quirk "
                                    "manufacturer_encoder_objects)")
    else:
        evidence.rests_on("cia", "CiA 406 6000h bit 0 (code sequence)")
    if encoder.access.dut.profile.entry(objects.operating, 0) is None:
        not_applicable(f"the profile has no operating parameters object {objects.operating:04X}h")
    shaft = _rotation(encoder)
    for ccw in (False, True):
        _set_code_sequence(encoder, ccw)
        settings = encoder.access.settings(functions=False)
        per_rev = units_per_rev(settings.geometry, settings.scaling)
        before = encoder.access.position()
        shaft.turn_by(STEP_UNITS / per_rev)  # clockwise
        after = encoder.access.position()
        moved = _signed_distance(before, after, settings.span)
        expected = -STEP_UNITS if ccw else STEP_UNITS
        evidence.note(f"code sequence {'CCW' if ccw else 'CW'}: {before} -> {after} for {STEP_UNITS} units "
                      "clockwise")
        assert moved == expected, (
            f"code sequence bit 0 = {int(ccw)}: a clockwise turn of {STEP_UNITS} units moved the position by "
            f"{moved}, expected {expected}")


def _scale(encoder) -> tuple[int, int]:
    """Switch scaling on (where 6000h has the bit) with ``_scaled_setting``; returns (MUR, TMR) written."""
    access, objects = encoder.access, encoder.access.objects
    mur, tmr = _scaled_setting(encoder)
    if objects.scaling_bit is not None:
        encoder.write(objects.operating, 0, (access.read_int(objects.operating) or 0) | 1 << objects.scaling_bit)
    encoder.write(objects.units_per_rev, 0, mur)
    if access.description.multiturn:
        encoder.write(objects.total_range, 0, tmr)
    return mur, tmr


def _scaled_setting(encoder) -> tuple[int, int]:
    """(MUR, TMR) other than the physical resolution: a quarter of the steps, the configured number of revolutions."""
    settings = encoder.access.settings(functions=False)
    mur = max(1, settings.geometry.steps_per_rev // 4)
    return mur, mur * max(1, settings.span // units_per_rev(settings.geometry, settings.scaling))


@pytest.mark.destructive
@pytest.mark.requires("scaling")
def test_scaling_sets_units_per_revolution(encoder, evidence):
    """A quarter revolution moves the position by a quarter of the physical steps 6501h with scaling off (where
    6000h has the scaling bit), and by a quarter of 6001h with scaling on."""
    objects = encoder.access.objects
    evidence.rests_on("cia" if not objects.relocated else "manual",
                      "CiA 406 6000h bit 2, 6001h, 6002h" if not objects.relocated
                      else f"the manual's scaling objects {objects.units_per_rev:04X}h/{objects.total_range:04X}h")
    shaft = _rotation(encoder)
    access = encoder.access
    if objects.scaling_bit is not None:  # scaling off first: the settings are put back with the bit still set
        operating = access.read_int(objects.operating) or 0
        if operating >> objects.scaling_bit & 1:
            encoder.write(objects.operating, 0, operating & ~(1 << objects.scaling_bit))
        _quarter_turn_moves(encoder, shaft, access.settings(functions=False).geometry.steps_per_rev // 4, "scaling off")
    mur, tmr = _scale(encoder)
    _quarter_turn_moves(encoder, shaft, mur // 4, f"scaling on, 6001h = {mur}, 6002h = {tmr}")


def _quarter_turn_moves(encoder, shaft, expected: int, setting: str) -> None:
    """Turn a quarter revolution (counting up) and check the position moved by ``expected`` units."""
    access = encoder.access
    settings = access.settings(functions=False)
    before = access.position()
    shaft.turn_by(-0.25 if settings.scaling.ccw else 0.25)
    after = access.position()
    moved = _signed_distance(before, after, settings.span)
    assert moved == expected, (
        f"{setting}: a quarter revolution moved the position by {moved} ({before} -> {after}), expected {expected}")


@pytest.mark.destructive
@pytest.mark.requires("scaling")
def test_scaled_position_stays_in_the_scaled_range(encoder, evidence):
    """With a scaled range set (6001h, 6002h), the position and a preset at its last unit stay inside it."""
    objects = encoder.access.objects
    evidence.rests_on("cia" if not objects.relocated else "manual", "CiA 406 6001h/6002h (total measuring range)")
    access = encoder.access
    mur, tmr = _scale(encoder)
    settings = access.settings(functions=False)
    low, high = settings.limits()
    position = access.position()
    assert low <= position <= high, f"6001h = {mur}, 6002h = {tmr}: position {position} outside {low} .. {high}"
    if not access.description.preset:
        return
    reached = encoder.preset(high)
    assert reached == high, f"preset {high} (the last unit of the scaled range): the position reads {reached}"


@pytest.mark.destructive
@pytest.mark.requires("scaling")
def test_module_identification_follows_the_range(encoder, evidence):
    """650Ah sub 2 / sub 3 (min/max position value) follow the measuring range set with 6001h/6002h, where the
    profile has them read-only (not constant)."""
    access = encoder.access
    profile = access.dut.profile
    entries = [profile.entry(od.MODULE_IDENTIFICATION, sub) for sub in (2, 3)]
    if any(e is None or e.access != "ro" for e in entries) or access.objects.relocated:
        not_applicable("650Ah sub 2/3 are absent or constant in the profile")
    source = profile.objects[od.MODULE_IDENTIFICATION].manual
    if source:
        evidence.rests_on("manual", f"650Ah ({source}): min/max position follow the measuring range")
    mur, tmr = _scale(encoder)
    access.wait_until_executed()
    low, high = access.settings(functions=False).limits()
    if access.description.module_max_is_range:
        documented_quirk(access.dut, fx.ModuleMaxIsRange, evidence, "650Ah sub 3 = the largest position value")
        high += 1
    expected = (low, high)
    observed = tuple(access.read_int(od.MODULE_IDENTIFICATION, sub) for sub in (2, 3))
    if observed != expected and not source:
        evidence.inferred_problem(f"650Ah sub 2/3 = {observed} with 6001h = {mur}, 6002h = {tmr}; the range is "
                                  f"{expected}", "650Ah min/max position follow the measuring range")
        return
    assert observed == expected, (
        f"6001h = {mur}, 6002h = {tmr}: 650Ah sub 2/3 = {observed}, the range is {expected[0]} .. {expected[1]}")


@pytest.mark.destructive
def test_operating_status_mirrors_operating_parameters(encoder, evidence):
    """6500h (operating status) shows the code sequence and scaling bits of 6000h, also after 6000h changed."""
    access = encoder.access
    if access.objects.relocated or None in (access.dut.profile.entry(od.OPERATING_STATUS, 0),
                                            access.dut.profile.entry(0x6000, 0)):
        not_applicable("the profile lacks 6500h (operating status) or 6000h (operating parameters)")
    evidence.rests_on("cia", "CiA 406 6500h (operating status: the 6000h settings in use)")
    mask = 0x01 | (1 << access.objects.scaling_bit if access.objects.scaling_bit is not None else 0)
    for ccw in (True, False):
        _set_code_sequence(encoder, ccw)
        operating, status = access.read_int(0x6000) or 0, access.read_int(od.OPERATING_STATUS) or 0
        assert status & mask == operating & mask, (
            f"6000h = {operating:04X}h but 6500h = {status:04X}h (bits {mask:02X}h must agree)")


def _position_tpdos(dut, index: int) -> list[tuple[int, int, int]]:
    """(comm index, byte offset, bits) of each TPDO whose readable mapping maps object ``index``."""
    found = []
    for comm in sorted(i for i in dut.profile.objects if 0x1800 <= i <= 0x19FF):
        mapping = comm + PDO_MAPPING_OFFSET
        if dut.profile.entry(mapping, 0) is None:
            continue
        bit = 0
        for sub in range(1, dut.read_uint(mapping, 0) + 1):
            entry = dut.read_uint(mapping, sub)
            if entry >> 16 == index and (entry >> 8) & 0xFF == 0:
                found.append((comm, bit // 8, entry & 0xFF))
                break
            bit += entry & 0xFF
    return found


def _sync_or_timer(dut, comm: int) -> tuple[int, int | None] | None:
    """How to make TPDO ``comm`` send with the shaft at rest: (transmission type to write, event timer in ms to
    write or None); None where neither SYNC nor an event timer can be set."""
    kind, timer = dut.profile.entry(comm, 2), dut.profile.entry(comm, 5)
    types = dut.profile.capabilities.tpdo_transmission_types
    if kind is not None and kind.writable and 1 in types:
        return 1, None
    current = dut.read_uint(comm, 2)
    if 1 <= current <= 240:
        return current, None
    if current in (254, 255) and timer is not None and timer.writable:
        return current, 20
    return None


@pytest.mark.requires("tpdos")
@pytest.mark.usefixtures("no_error_left")  # NMT start: no error may hold the device out of operational
def test_position_in_tpdo_equals_sdo(encoder, dut, settings_journal, back_to_preoperational, evidence, pytestconfig):
    """With the shaft at rest, the position a TPDO carries equals 6004h read by SDO before and after it (after a
    preset away from the raw counts, where destructive changes are allowed)."""
    evidence.rests_on("cia", "CiA 301 §7.2.2 (PDO carries the mapped object's value), CiA 406 6004h")
    if encoder.access.description.preset and settings_of(pytestconfig).allow_destructive:
        settings = encoder.access.settings(functions=False)
        encoder.preset(settings.shown(unsigned_in_span(encoder.access.position() + settings.span // 3,
                                                       settings.span)))
    candidates = [(c, o, b, how) for c, o, b in _position_tpdos(dut, encoder.access.objects.position)
                  if (how := _sync_or_timer(dut, c)) is not None]
    if not candidates:
        not_applicable("no TPDO maps the position object with a SYNC type or a settable event timer")
    comm, offset, bits, (kind, timer) = candidates[0]
    tpdo = TpdoUnderTest(dut, settings_journal, comm, kind)
    cob_id = tpdo.cob_id()
    can_id = can_id_of(cob_id)
    enable = None
    if cob_id & COB_ID_INVALID:
        if not tpdo.writable(1):
            not_applicable(f"{comm:04X}h is disabled and its COB-ID is read-only")
        enable = cob_id_valid(cob_id)
    tpdo.configure(cob_id=enable, trans_type=kind, event_timer=timer)
    before = encoder.access.position()
    dut.nmt.transition("operational", settings_journal, evidence)
    mark = dut.frames.mark()
    if 1 <= kind <= 240:
        for _ in range(kind):
            dut.send_sync()
    pdo = dut.frames.wait_for(tpdo.frames(can_id), 2.0, mark)
    after = encoder.access.position()
    assert pdo is not None, f"no TPDO on {can_id:03X}h ({comm:04X}h type {kind}) after start" + (
        " and SYNC" if 1 <= kind <= 240 else "")
    raw = int.from_bytes(bytes(pdo.data[offset:offset + bits // 8]), "little")
    flags = encoder.access.description.flags
    if flags is not None and "tpdo" in flags.channels:
        raw &= flags.position_mask
    if encoder.access.description.signed and raw >= 1 << (bits - 1):
        raw -= 1 << bits
    evidence.note(f"SDO {before} / TPDO {raw} / SDO {after}: {format_frames([pdo])}")
    assert before == after, f"the position changed while the shaft was at rest ({before} -> {after})"
    assert raw == before, f"TPDO {can_id:03X}h carries position {raw}, SDO 6004h reads {before}"


@pytest.mark.destructive
@pytest.mark.requires("speed")
def test_speed_value_in_measuring_units_per_second(encoder, evidence):
    """6030h sub 1 shows the shaft speed in measuring units per second (times the device's speed factor), signed
    by the code sequence."""
    access = encoder.access
    if access.description.speed_scaling_object is not None:
        documented_quirk(access.dut, fx.SpeedScalingObject, evidence, "CiA 406 6030h units per second")
        evidence.rests_on("manual", "the manual's speed unit (quirk speed_scaling_object)")
    else:
        evidence.rests_on("cia", "CiA 406 6030h (speed value)")
    shaft = _rotation(encoder)
    drive = shaft.drive
    speed = 0.25  # rev/s: inside the 16-bit range at every resolution up to 2^17 units per revolution
    drive.set_speed(speed)
    try:
        expected = encoder.reference().speed(speed)
        deadline = Deadline(SPEED_SETTLE_S)
        tolerance = max(2, abs(expected) // 50)
        while True:
            observed = access.read_int(od.SPEED, 1)
            assert observed is not None
            if abs(observed - expected) <= tolerance or deadline.expired():
                break
    finally:
        drive.set_speed(0.0)
    evidence.measure("speed value 6030h.01", observed, "units/s", expected - tolerance, expected + tolerance)
    assert abs(observed - expected) <= tolerance, (
        f"shaft at {speed} rev/s: 6030h.01 = {observed}, expected {expected} +- {tolerance} (units per second"
        f"{' times the speed factor' if access.description.speed_scaling_object else ''})")


@pytest.mark.destructive
@pytest.mark.usefixtures("no_error_left")  # NMT start: no error may hold the device out of operational
def test_limit_switch_flags_in_the_process_value(encoder, dut, settings_journal, back_to_preoperational, evidence):
    """Documented quirk: enabled limit switches set their flag bit in the process value a TPDO carries while the
    position is beyond the limit (Min: below, Max: above), and clear it when the limit moves past the position."""
    params = documented_quirk(dut, fx.LimitSwitchFlags, evidence, "CiA 406 position value is a plain count")
    mapping = dut.profile.params_of(fx.FixedTpdoMapping)
    sync = mapping.sync_tpdos[0] if mapping is not None and mapping.sync_tpdos else None
    if sync is None or "tpdo" not in params.applies_to:
        not_applicable("no fixed SYNC TPDO carries the process value")
    evidence.rests_on("manual", "the manual's limit switches (quirk limit_switch_flags)")
    access = encoder.access
    tpdo = dut.tpdo.at(sync.tpdo)
    cob_id = tpdo.can_id()
    every = max(1, dut.read_uint(sync.tpdo, sync.counter_subindex))
    settings = access.settings(functions=False)
    if access.description.preset:  # room on both sides of the position for the limits
        position = encoder.preset(settings.shown(settings.span // 2))
    position = access.position()
    if not 100 <= position < settings.span - 100:
        not_applicable(f"the position {position} leaves no room for a limit on both sides (no preset)")
    enable = dut.read_uint(params.enable_object, 0)
    switches = [(s, below) for s, below in ((params.min, True), (params.max, False)) if s is not None]
    for switch, _ in switches:
        encoder.write(params.enable_object, 0, enable | 1 << switch.enable_bit)
        enable |= 1 << switch.enable_bit
    dut.nmt.transition("operational", settings_journal, evidence)
    problems = []
    for switch, below in switches:
        for beyond in (True, False):  # position beyond the limit, then the limit moved past the position
            limit = position + 100 if below == beyond else position - 100
            encoder.write(switch.object, 0, limit)
            mark = dut.frames.mark()
            for _ in range(every):
                dut.send_sync()
            frame = dut.frames.wait_for(tpdo.frames(cob_id), 1.0, mark)
            if frame is None:
                problems.append(f"no TPDO {cob_id:03X}h after {every} SYNC(s)")
                break
            flag = bool(int.from_bytes(bytes(frame.data[:4]), "little") >> switch.flag_bit & 1)
            where = f"position {position}, limit {switch.object:04X}h = {limit}"
            if flag != beyond:
                problems.append(f"{where}: bit {switch.flag_bit} = {int(flag)}, expected {int(beyond)}")
    assert not problems, "limit-switch flags in the process value:\n" + "\n".join(problems)


@pytest.mark.destructive
def test_zeroing_object_zeroes_once_per_rearm(encoder, evidence):
    """Documented quirk: writing the trigger value to the zeroing object sets the position to 0 (with the preset
    at 0); writing it again does nothing until the re-arm value was written."""
    params = documented_quirk(encoder.access.dut, fx.ZeroingObject, evidence, "no zeroing object besides 6003h")
    evidence.rests_on("manual", "the manual's zeroing object (quirk zeroing_object)")
    shaft = _rotation(encoder)
    access = encoder.access
    encoder.preset(0)  # the manual's condition: preset value 0
    index, sub = params.index, params.subindex
    settings = access.settings(functions=False)
    per_rev = units_per_rev(settings.geometry, settings.scaling)
    steps = []

    def turn_and_write(value: int) -> int:
        shaft.turn_by(STEP_UNITS / per_rev * (-1 if settings.scaling.ccw else 1))
        before = access.position()
        encoder.write(index, sub, value)
        after = access.position_when(0, timeout=params.duration_ms / 1000)
        steps.append(f"{before} -> write {value} -> {after}")
        return after

    encoder.write(index, sub, params.rearm_value)
    zeroed = turn_and_write(params.trigger_value)
    assert zeroed == 0, f"{index:04X}h = {params.trigger_value} must zero the position: {'; '.join(steps)}"
    again = turn_and_write(params.trigger_value)
    assert again != 0, (f"{index:04X}h = {params.trigger_value} a second time without {params.rearm_value} first "
                        f"must not zero again: {'; '.join(steps)}")
    encoder.write(index, sub, params.rearm_value)
    rearmed = turn_and_write(params.trigger_value)
    assert rearmed == 0, f"after {params.rearm_value}, {params.trigger_value} must zero again: {'; '.join(steps)}"
