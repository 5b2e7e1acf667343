"""CAM switch (CiA 406 6300h..6337h): state per cam from the position, its window, polarity, enable and hysteresis.

Every test writes the CAM settings of channel 1 (high limits before low limits, where the device
refuses a low limit that is not below its high limit), puts the position where each check needs it
by presetting (no rotation needed, so the tests run on a bench without a motor) and compares 6300h
sub 1 with the reference model (``models.encoder.cam``) fed with the settings read back from the
device, step by step so that the hysteresis history is the device's. What each rule rests on:

- window, polarity, enable: CiA 406 6300h..6302h, 6310h..6327h (WDGA M §7.5);
- the window edges belong to the window: our inference (WDGA example CAM1 0..2048, CAM2 2049..4095);
- a disabled cam reads 0: our inference ("only enabled cams can change state", M §7.5, is firm);
- hysteresis: holding past the edge when leaving is firm (CiA 406 6330h..6337h, M §7.5.6); where an
  inactive cam switches on (at the edge) is our inference;
- a low limit above the high limit: refused where the manual says so (quirk ``cam_low_below_high``),
  elsewhere only observed (CiA 406 v3.2, objects 6310h-6317h CAM low limit and 6320h-6327h CAM high limit, does
  not say how a window with the low limit above the high limit reads; vendors differ).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import replace

import pytest

from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.bench import EncoderBench
from encoder_conformance.dut.link import format_frames
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.dut.tpdo import (
    MappingCustody,
    NoUsableTpdo,
    TpdoUnderTest,
    apply_mapping,
    choose_tpdo,
    describe,
)
from encoder_conformance.models.encoder import objects as od
from encoder_conformance.models.encoder.cam import Cam
from encoder_conformance.models.encoder.position import units_per_rev
from encoder_conformance.plugin.evidence import Evidence
from encoder_conformance.plugin.skips import not_applicable, skip_text
from encoder_conformance.plugin.suite_helpers import (
    CHANNEL,
    WINDOW_RULE,
    CamChannel,
    Findings,
    Remapped,
    abort_accepted,
    cam_names,
)
from encoder_conformance.profile import quirk_effects as fx

# the position is put by preset (capability preset), so the tests run on a bench without a motor
pytestmark = [pytest.mark.spec("CiA 406 6300h-6337h (CAM)"), pytest.mark.requires("cam", "preset"),
              pytest.mark.destructive]

EDGE_RULE = "the window edges belong to the window (WDGA M §7.5 example: CAM1 0..2048, CAM2 2049..4095)"
DISABLED_RULE = "a disabled cam's state bit reads 0 (WDGA M §7.5 says only that it cannot change state)"
SWITCH_ON_RULE = ("with hysteresis an inactive cam switches on at the window edge (CiA 406 names only the "
                  "'hysteresis of the switching points')")
LEAVING_RULE = ("with hysteresis a cam stays on up to the full hysteresis past the edge it leaves by (a band "
                "centred on the edge would end at half of it)")
HYSTERESIS_RULE = "CiA 406 6330h-6337h (hysteresis of the switching points), WDGA M §7.5.6"
MANUAL_EXAMPLE_ENABLE = 0x4A  # M §7.5.2: CAM2 + CAM4 + CAM7
MANUAL_EXAMPLE_POLARITY = 0x13  # M §7.5.3: CAM1, CAM2, CAM5 inverted


@pytest.fixture
def cam_channel(encoder: EncoderBench, evidence: Evidence) -> CamChannel:
    """CAM channel 1 of the device (put back after the test by the encoder fixture)."""
    dut = encoder.access.dut
    cam = dut.profile.capabilities.cam
    assert cam is not None  # requires("cam")
    high_first = dut.profile.params_of(fx.CamLowBelowHigh) is not None
    if high_first:
        found = dut.profile.quirk(fx.CamLowBelowHigh)
        assert found is not None
        evidence.deviation(found.id, found.quirk.title + " (high limits written first)")
    settings = encoder.access.settings()
    return CamChannel(encoder, cam.cams_per_channel, high_first, settings.span, settings.limits()[0])


def _mid(cam: Cam) -> int:
    return (cam.low + cam.high) // 2


def test_each_cam_alone_follows_its_window(cam_channel: CamChannel, evidence: Evidence) -> None:
    """Each cam enabled alone: its bit is set inside its window, clear below and above it (CiA 406 6300h/6301h)."""
    cams = cam_channel.windows()
    reference = cam_channel.configure(cams, enable=0)
    findings = Findings()
    for number, cam in cams.items():
        cam_channel.set_registers(reference, enable=1 << number)
        gap = (cam.high - cam.low) // 2
        for label, position in (("below", cam.low - gap), ("inside", _mid(cam)), ("above", cam.high + gap)):
            observed, expected = cam_channel.visit(reference, position)
            findings.compare(f"CAM{number + 1} alone [{cam.low}, {cam.high}], {label} at {position}", observed,
                             expected)
    findings.report(evidence)


def test_several_cams_together_manual_example(cam_channel: CamChannel, evidence: Evidence) -> None:
    """The manual's example (CAM1 0..180°, CAM2 180°..360°, CAM3 0..60°, enable 07h) in the current units per
    revolution: the state byte combines the cams (WDGA M §7.5, T 8.67-8.74; CiA 406 6300h)."""
    if cam_channel.count < 3:
        not_applicable(f"the example needs 3 cams, the channel has {cam_channel.count}")
    settings = cam_channel.encoder.access.settings()
    rev = units_per_rev(settings.geometry, settings.scaling)
    if rev < 12:
        not_applicable(f"{rev} units per revolution cannot carry the example's 60° and 180° points")
    half, sixth = rev * 2048 // 4096, rev * 682 // 4096  # 2048 and 682 of the manual's 4096 units
    cams = {0: Cam(0, half), 1: Cam(half + 1, rev - 1), 2: Cam(0, sixth)}
    reference = cam_channel.configure(cams, enable=0x07)
    evidence.note(f"{rev} units per revolution: CAM1 [0, {half}], CAM2 [{half + 1}, {rev - 1}], CAM3 [0, {sixth}]; "
                  "the manual (4096 units) expects 05h at 0..682, 01h at 683..2048, 02h at 2049..4095")
    low, high = settings.limits()
    edges = {0: {0: EDGE_RULE, 2: EDGE_RULE}, sixth: {2: EDGE_RULE}, half: {0: EDGE_RULE},
             half + 1: {1: EDGE_RULE}, rev - 1: {1: EDGE_RULE}}
    positions = sorted({0, rev * 100 // 4096, sixth, sixth + 1, rev * 1000 // 4096, half, half + 1,
                        rev * 3000 // 4096, rev - 1, rev})
    findings = Findings()
    for position in positions:
        if not low <= position <= high:
            continue
        observed, expected = cam_channel.visit(reference, position)
        findings.compare(f"at {position}", observed, expected, edges.get(position))
    findings.report(evidence, ("cia", WINDOW_RULE + "; WDGA M §7.5, T 8.67-8.74"))


def test_window_edges_belong_to_the_window(cam_channel: CamChannel, evidence: Evidence) -> None:
    """Every cam enabled: clear at low-1 and high+1, set at low+1 and high-1 (CiA 406 6310h/6320h), set at low and
    high (inferred)."""
    cams = cam_channel.windows()
    reference = cam_channel.configure(cams, enable=(1 << cam_channel.count) - 1)
    findings = Findings()
    for number, cam in cams.items():
        for label, position in (("low-1", cam.low - 1), ("low", cam.low), ("low+1", cam.low + 1),
                                ("high-1", cam.high - 1), ("high", cam.high), ("high+1", cam.high + 1)):
            observed, expected = cam_channel.visit(reference, position)
            edge = {number: EDGE_RULE} if position in (cam.low, cam.high) else None
            findings.compare(f"CAM{number + 1} [{cam.low}, {cam.high}] at {label} = {position}", observed, expected,
                             edge)
    findings.report(evidence)


def test_polarity_inverts_state(cam_channel: CamChannel, evidence: Evidence) -> None:
    """Polarity 13h (the manual's example), then its complement: an inverted cam reads 0 inside its window and
    1 outside (CiA 406 6302h, WDGA M §7.5.3)."""
    cams = cam_channel.windows()
    everything = (1 << cam_channel.count) - 1
    reference = cam_channel.configure(cams, enable=everything, polarity=MANUAL_EXAMPLE_POLARITY & everything)
    findings = Findings()
    for polarity in (MANUAL_EXAMPLE_POLARITY & everything, ~MANUAL_EXAMPLE_POLARITY & everything):
        cam_channel.set_registers(reference, polarity=polarity)
        outside = cam_channel.outside(cams)
        observed, expected = cam_channel.visit(reference, outside)
        findings.compare(f"polarity {polarity:02X}h, outside every window at {outside}", observed, expected)
        for number, cam in cams.items():
            observed, expected = cam_channel.visit(reference, _mid(cam))
            findings.compare(f"polarity {polarity:02X}h, inside CAM{number + 1} at {_mid(cam)}", observed, expected)
    findings.report(evidence, ("cia", "CiA 406 6302h (CAM polarity), WDGA M §7.5.3"))


def test_disabled_cam_reads_zero_whatever_polarity(cam_channel: CamChannel, evidence: Evidence) -> None:
    """Enable 4Ah (the manual's example) with polarity FFh and 00h: enabled cams follow their windows, disabled
    cams never change (WDGA M §7.5.2, CiA 406 6301h) and read 0 (inferred)."""
    cams = cam_channel.windows()
    everything = (1 << cam_channel.count) - 1
    enable = MANUAL_EXAMPLE_ENABLE & everything
    disabled = everything & ~enable
    reference = cam_channel.configure(cams, enable=enable, polarity=everything)
    findings = Findings()
    for polarity in (everything, 0):
        cam_channel.set_registers(reference, polarity=polarity)
        seen: dict[int, set[int]] = {n: set() for n in range(cam_channel.count) if disabled >> n & 1}
        positions = [("outside every window", cam_channel.outside(cams))]
        positions += [(f"inside CAM{n + 1}", _mid(cam)) for n, cam in cams.items()]
        for label, position in positions:
            observed, expected = cam_channel.visit(reference, position)
            findings.compare(f"enable {enable:02X}h, polarity {polarity:02X}h, {label} at {position}",
                             observed & enable, expected & enable)
            for number, values in seen.items():
                values.add(observed >> number & 1)
        changed = [n for n, values in seen.items() if len(values) > 1]
        if changed:
            findings.hard.append(f"polarity {polarity:02X}h: disabled {cam_names(sum(1 << n for n in changed))} "
                                 "changed state with the position (only enabled cams can change state, WDGA M §7.5.2)")
        ones = [n for n, values in seen.items() if values == {1}]
        if ones:
            evidence.inferred_problem(
                f"polarity {polarity:02X}h: disabled {cam_names(sum(1 << n for n in ones))} read 1", DISABLED_RULE)
    findings.report(evidence, ("cia", "CiA 406 6301h (CAM enable), WDGA M §7.5.2"))


def test_enable_switches_cam_on_and_off(cam_channel: CamChannel, evidence: Evidence) -> None:
    """Each cam, the position inside its window: enabling sets its bit, disabling clears it and the bit no longer
    follows the position, enabling again brings it back (CiA 406 6301h, WDGA M §7.5.2)."""
    cams = cam_channel.windows()
    reference = cam_channel.configure(cams, enable=0)
    findings = Findings()
    outside = cam_channel.outside(cams)
    for number, cam in cams.items():
        inside, bit = _mid(cam), 1 << number
        cam_channel.move(inside)
        reference.cam_state(inside, CHANNEL)
        cam_channel.set_registers(reference, enable=bit)
        findings.compare(f"CAM{number + 1} enabled, inside at {inside}", cam_channel.state(),
                         reference.cam_state(inside, CHANNEL))
        cam_channel.set_registers(reference, enable=0)
        on_disable = cam_channel.state()
        findings.compare(f"CAM{number + 1} disabled, inside at {inside}", on_disable,
                         reference.cam_state(inside, CHANNEL), {number: DISABLED_RULE})
        observed, expected = cam_channel.visit(reference, outside)
        if (observed ^ on_disable) & bit:
            findings.hard.append(f"CAM{number + 1} disabled: its bit changed from {on_disable >> number & 1} inside "
                                 f"to {observed >> number & 1} outside (only enabled cams can change state)")
        findings.compare(f"CAM{number + 1} disabled, outside at {outside}", observed, expected,
                         {number: DISABLED_RULE})
        cam_channel.set_registers(reference, enable=bit)
        observed, expected = cam_channel.visit(reference, inside)
        findings.compare(f"CAM{number + 1} enabled again, inside at {inside}", observed, expected)
    findings.report(evidence, ("cia", "CiA 406 6301h (CAM enable), WDGA M §7.5.2"))


def _hysteresis_path(cams: Iterable[Cam]) -> list[int]:
    """Positions around each window and its hysteresis band, ascending: every edge, one inside and one beyond."""
    points: set[int] = set()
    for cam in cams:
        h = cam.hysteresis
        for edge in (cam.low - h, cam.low, cam.high, cam.high + h):
            points.update((edge - 1, edge, edge + 1))
        points.update((cam.low - h - 3, (cam.low + cam.high) // 2, cam.high + h + 3))
    return sorted(points)


def _where(position: int, cams: Mapping[int, Cam]) -> str:
    """``position`` named by the nearest switching point: 'CAM1 high+h+1'."""
    points = {}
    for number, cam in cams.items():
        h = cam.hysteresis
        points.update({cam.low - h: f"CAM{number + 1} low-h", cam.low: f"CAM{number + 1} low",
                       cam.high: f"CAM{number + 1} high", cam.high + h: f"CAM{number + 1} high+h"})
    edge = min(points, key=lambda point: abs(point - position))
    offset = position - edge
    return points[edge] + (f"{offset:+d}" if offset else "")


def _hysteresis_rules(position: int, cam: Cam, upward: bool) -> str | None:
    """The inferred rule alone deciding the cam's bit at ``position`` on a pass from outside the band through the
    window (``upward`` or down), or None where every reading of 'hysteresis of the switching points' agrees.

    Readings we know: switch on at the edge and off h past it (the model's), both switching points shifted h
    in the direction of travel, and a band of h centred on each edge. They agree that a cam entering its
    window is on once h inside it, stays on up to h/2 past the edge it leaves by, and is off more than h past
    it; between those points the outcome depends on the reading (inferred).
    """
    h = cam.hysteresis
    if position in (cam.low, cam.high, cam.low - h, cam.high + h):
        return EDGE_RULE
    entering_edge, leaving_edge = (cam.low, cam.high) if upward else (cam.high, cam.low)
    sign = 1 if upward else -1
    inside_from_entry = (position - entering_edge) * sign  # > 0: past the edge the pass came in by
    past_exit = (position - leaving_edge) * sign  # > 0: past the edge the pass leaves by
    if 0 <= inside_from_entry < h and past_exit <= 0:
        return SWITCH_ON_RULE
    if h / 2 < past_exit <= h:
        return LEAVING_RULE
    return None


def test_hysteresis_holds_when_leaving_both_directions(cam_channel: CamChannel, evidence: Evidence) -> None:
    """Moving up through two windows and down again in small steps: a cam with hysteresis h is on once h inside
    the window it enters, stays on up to h/2 past the edge it leaves by and is off beyond h (CiA 406 6330h, WDGA
    M §7.5.6: every reading agrees there); where the readings differ (switch-on point, h/2..h past the edge) the
    model's reading is inferred."""
    windows = cam_channel.windows()
    width = windows[0].high - windows[0].low
    last = cam_channel.count - 1
    cams = {0: replace(windows[0], hysteresis=max(1, width // 4))}
    if last:
        cams[last] = replace(windows[last], hysteresis=max(1, width // 3))
    enable = sum(1 << n for n in cams)
    reference = cam_channel.configure(cams, enable=enable)
    evidence.note("; ".join(f"CAM{n + 1} [{c.low}, {c.high}] hysteresis {c.hysteresis}" for n, c in cams.items()))
    path = _hysteresis_path(cams.values())
    findings = Findings()
    start = min(path) - 1  # below every band: no history on the device or in the model
    observed, expected = cam_channel.visit(reference, start)
    findings.compare(f"start at {start}", observed, expected)
    for direction, positions in (("up", path), ("down", path[::-1])):
        for position in positions:
            rules = {n: _hysteresis_rules(position, cam, direction == "up") for n, cam in cams.items()}
            observed, expected = cam_channel.visit(reference, position)
            findings.compare(f"moving {direction}, at {position} ({_where(position, cams)})", observed, expected,
                             {n: rule for n, rule in rules.items() if rule is not None})
    findings.report(evidence, ("cia", HYSTERESIS_RULE))


def _raw_write(cam_channel: CamChannel, index: int, value: int) -> sdo_frames.SdoResponse:
    """Write ``value`` without raising on an abort; the old value is put back after the test."""
    encoder = cam_channel.encoder
    encoder.journal.remember(index, CHANNEL)
    request = sdo_frames.expedited_download_request(index, CHANNEL, encoder.access.encode(index, CHANNEL, value))
    response = cam_channel.dut.sdo_request(request)
    assert response is not None, f"{index:04X}h.{CHANNEL:02X} = {value}: no SDO answer"
    return response


def test_low_limit_above_high_limit(cam_channel: CamChannel, evidence: Evidence) -> None:
    """Low limit at or above the high limit: refused where the manual says so (quirk cam_low_below_high, WDGA
    M §7.5.4); elsewhere CiA 406 leaves it open and the outcome (wrap-around, swap, refused) is only noted."""
    cams = cam_channel.windows()
    found = cam_channel.dut.profile.quirk(fx.CamLowBelowHigh)
    if found is None:
        _observe_low_above_high(cam_channel, cams[0], evidence)
        return
    quirk_id, quirk, params = found.id, found.quirk, found.params
    evidence.deviation(quirk_id, quirk.title)
    cam_channel.configure(cams, enable=0)
    problems: list[str] = []
    for number, cam in cams.items():
        low_object = od.cam_limit_objects(number)[0]
        for label, low in (("above", cam.high + 1), ("equal to", cam.high)):
            response = _raw_write(cam_channel, low_object, low)
            what = f"CAM{number + 1} low limit {low_object:04X}h = {low}, {label} the high limit {cam.high}"
            if not response.is_abort:
                problems.append(f"{what}: accepted ({response.describe()})")
            elif not abort_accepted(cam_channel.dut, response, {params.abort_code}):
                evidence.inferred_problem(f"{what}: {response.describe()}",
                                          f"abort {sdo_frames.abort_name(params.abort_code)} (quirk {quirk_id}: the "
                                          "manual gives no code)")
            kept = cam_channel.encoder.access.read_int(low_object, CHANNEL)
            if response.is_abort and kept != cam.low:
                problems.append(f"{what}: refused, but the low limit reads {kept}, was {cam.low}")
    evidence.rests_on("manual", f"WDGA M §7.5.4, §8.11 (quirk {quirk_id})")
    assert not problems, "a low limit not below the high limit must be refused:\n" + "\n".join(problems)


def _observe_low_above_high(cam_channel: CamChannel, cam: Cam, evidence: Evidence) -> None:
    """No verdict: note whether the device refuses low > high, or how it reads such a window."""
    evidence.rests_on("inferred", "CiA 406 v3.2, objects 6310h-6317h and 6320h-6327h (CAM low / high limit): a low "
                      "limit above the high limit is left open")
    swapped = Cam(cam.high, cam.low)
    cam_channel.configure({0: Cam(cam.low, cam.high)}, enable=1)
    high_object, low_object = od.cam_limit_objects(0)[1], od.cam_limit_objects(0)[0]
    cam_channel.encoder.write(high_object, CHANNEL, swapped.high)
    response = _raw_write(cam_channel, low_object, swapped.low)
    if response.is_abort:
        evidence.note(f"CAM1 low {swapped.low} above high {swapped.high}: refused ({response.describe()})")
        return
    states = {}
    for label, position in (("below both", swapped.high - 1), ("between", _mid(cam)), ("above both", swapped.low + 1)):
        cam_channel.move(position)
        states[label] = cam_channel.state() & 1
    shape = {(1, 0, 1): "a wrap-around window", (0, 1, 0): "the limits swapped", (0, 0, 0): "never active"}
    observed = (states["below both"], states["between"], states["above both"])
    evidence.note(f"CAM1 low {swapped.low} above high {swapped.high}: accepted; CAM1 bit below / between / above "
                  f"= {observed}: {shape.get(observed, 'none of wrap-around, swap, off')}")


def test_low_limit_before_high_limit_refused(cam_channel: CamChannel, evidence: Evidence) -> None:
    """Documented write order: a low limit written before its cam's high limit was raised above it is refused;
    high limit first, then low limit, is accepted (WDGA M §7.5.4, §8.11)."""
    found = cam_channel.dut.profile.quirk(fx.CamLowBelowHigh)
    if found is None:
        not_applicable("CiA 406 CAM limits are independent objects (no quirk cam_low_below_high)")
    quirk_id, quirk = found.id, found.quirk
    evidence.deviation(quirk_id, quirk.title)
    cams = cam_channel.windows()
    cam_channel.configure(cams, enable=0)
    problems: list[str] = []
    for number, cam in cams.items():
        low_object, high_object, _ = od.cam_limit_objects(number)
        moved = Cam(cam.high + 1, cam.high + 1 + (cam.high - cam.low))
        response = _raw_write(cam_channel, low_object, moved.low)
        if not response.is_abort:
            problems.append(f"CAM{number + 1}: low limit {moved.low} written before the high limit (still "
                            f"{cam.high}): accepted")
        cam_channel.encoder.write(high_object, CHANNEL, moved.high)
        response = _raw_write(cam_channel, low_object, moved.low)
        if response.is_abort:
            problems.append(f"CAM{number + 1}: low limit {moved.low} after the high limit {moved.high}: "
                            f"{response.describe()}")
        read_back = tuple(cam_channel.encoder.access.read_int(index, CHANNEL) for index in (low_object, high_object))
        if read_back != (moved.low, moved.high):
            problems.append(f"CAM{number + 1}: limits read {read_back}, written ({moved.low}, {moved.high})")
    evidence.rests_on("manual", f"WDGA M §7.5.4, §8.11 (quirk {quirk_id})")
    assert not problems, "CAM limit write order:\n" + "\n".join(problems)


# -- CAM state in a TPDO ----------------------------------------------------------------------------------

@pytest.fixture
def cam_tpdo(cam_channel: CamChannel, evidence: Evidence) -> Iterator[Remapped]:
    """A TPDO mapped with 6300h sub 1 alone, sent on every SYNC; afterwards pre-operational and the mapping back
    (CiA 301 order: PDO invalid, sub 0 = 0, entries, sub 0, COB-ID)."""
    dut, journal = cam_channel.dut, cam_channel.encoder.journal
    state = dut.profile.entry(od.CAM_STATE, CHANNEL)
    if state is None or not state.pdo_mappable:
        not_applicable(f"6300h.{CHANNEL:02X} is not PDO-mappable in the profile")
    if 1 not in dut.profile.capabilities.tpdo_transmission_types:
        not_applicable("the profile does not list TPDO transmission type 1")
    try:
        choice = choose_tpdo(dut, 2, [1])
    except NoUsableTpdo as exc:
        skip_text(str(exc), exc.hold)
    tpdo = TpdoUnderTest(dut, journal, choice.comm, choice.transmission_type)
    comm, mapping = tpdo.comm, tpdo.mapping_index
    entries = [dut.profile.entry(mapping, sub) for sub in (0, 1)] + [dut.profile.entry(comm, 1)]
    if any(e is None or not e.writable for e in entries):
        not_applicable(f"{mapping:04X}h sub 0/1 or {comm:04X}h.01 not writable")
    for note in choice.notes:
        evidence.note(note)
    with MappingCustody(dut, comm):
        before = tpdo.mapping()
        tpdo.configure(trans_type=1)  # sub 2 is writable: the choice asked for it
        apply_mapping(dut, comm, [(od.CAM_STATE, CHANNEL, 8)])
        evidence.note(f"{mapping:04X}h = [63000{CHANNEL}08h] (6300h.{CHANNEL:02X}, 8 bit), {comm:04X}h.02 = 1, "
                      f"mapping before {describe(before)}")
        yield Remapped(comm, tpdo.can_id())
        if dut.usable:
            dut.nmt.back_to_preoperational()


@pytest.mark.usefixtures("no_error_left")  # NMT start: no error may hold the device out of operational
def test_cam_state_in_tpdo_matches_sdo(cam_channel: CamChannel, cam_tpdo: Remapped, settings_journal,
                                       evidence: Evidence, dut: DeviceUnderTest) -> None:
    """6300h sub 1 mapped into a TPDO: after each SYNC the PDO carries the state 6300h shows over SDO and the model
    expects (CiA 406 6300h PDO-mappable, CiA 301 §7.2.2; WDGA T 6.6)."""
    cams = cam_channel.windows()
    reference = cam_channel.configure(cams, enable=(1 << cam_channel.count) - 1)
    dut.nmt.transition("operational", settings_journal, evidence)
    problems: list[str] = []
    positions = [cam_channel.outside(cams), *(_mid(cam) for cam in list(cams.values())[:3])]
    window = dut.sdo_timeout + dut.profile.timing.nmt_settle_ms / 1000
    for position in positions:
        observed, expected = cam_channel.visit(reference, position)
        mark = dut.send_sync()
        frame = dut.frames.wait_for(dut.tpdo.at(cam_tpdo.comm).frames(cam_tpdo.cob_id), window, mark)
        if frame is None:
            problems.append(f"at {position}: no TPDO {cam_tpdo.cob_id:03X}h after SYNC\n"
                            f"{format_frames(dut.frames.since(mark)[:10])}")
            break
        carried = frame.data[0] if frame.data else None
        if carried != observed or carried != expected:
            problems.append(f"at {position}: TPDO {cam_tpdo.cob_id:03X}h carries {frame.data.hex(' ').upper()}, "
                            f"6300h.{CHANNEL:02X} by SDO {observed:02X}h, the model {expected:02X}h")
    evidence.rests_on("cia", "CiA 406 6300h (PDO-mappable), CiA 301 §7.2.2 (PDO mapping); WDGA T 6.6")
    assert not problems, "CAM state in the TPDO:\n" + "\n".join(problems)
