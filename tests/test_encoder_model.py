"""Property tests of the encoder reference model (encoder_conformance/models/encoder) against its own invariants.

Each test states a property the CiA 406 encoder function must have (or a documented consequence of
the model's rules) and checks it over generated settings; none of them re-implements the model's
arithmetic. Hypothesis settings come from the profiles in conftest.py (dev / ci / bench); the
``max_examples`` below only raise the count for the cheap core properties.
"""

from __future__ import annotations

import math
from fractions import Fraction

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import encoder_conformance.models.encoder.objects as od
from encoder_conformance.models.encoder.cam import Cam, CamChannel, CamRules, CamTracker, cam_state, inside
from encoder_conformance.models.encoder.objects import EncoderObjects
from encoder_conformance.models.encoder.position import (
    EncoderGeometry,
    Scaling,
    counts_for_position,
    counts_value,
    position_limits,
    position_span,
    position_value,
    preset_offset,
    raw_counts,
    signed_half_range,
    turns_for_counts,
    unsigned_in_span,
)
from encoder_conformance.models.encoder.reference import EncoderReference
from encoder_conformance.models.encoder.settings import (
    DEFAULT_STEPS_PER_REV,
    EncoderDescription,
    EncoderSettings,
    read_settings,
)
from encoder_conformance.models.encoder.speed import S16_MAX, S16_MIN, speed_value
from encoder_conformance.models.encoder.work_area import ABOVE, BELOW, area_state

MANY = settings(max_examples=max(200, settings().max_examples))  # never fewer than the profile

# -- strategies --------------------------------------------------------------------------------

#: steps per revolution: the usual powers of two and anything else a device may report
steps_per_rev = st.one_of(st.sampled_from([1 << n for n in range(17)]), st.integers(1, 70_000))
#: revolutions of a multiturn device
revolutions = st.one_of(st.sampled_from([1 << n for n in range(15)]), st.integers(2, 5_000))
#: shaft angles in turns, far beyond the physical range in both directions
turns = st.floats(-20_000, 20_000, allow_nan=False, allow_infinity=False)


@st.composite
def geometries(draw: st.DrawFn, multiturn: bool | None = None) -> EncoderGeometry:
    """A sensor, singleturn (1 revolution) or multiturn."""
    if multiturn is None:
        multiturn = draw(st.booleans())
    return EncoderGeometry(draw(steps_per_rev), draw(revolutions) if multiturn else 1)


@st.composite
def scalings(draw: st.DrawFn, geometry: EncoderGeometry, enabled: bool | None = None) -> Scaling:
    """Any user settings: code sequence, scaling bit, MUR (0: not set), TMR (0: not set), an offset in range."""
    mur = draw(st.integers(0, 4 * geometry.steps_per_rev))
    physical = geometry.revolutions * mur
    scaling = Scaling(
        ccw=draw(st.booleans()),
        enabled=draw(st.booleans()) if enabled is None else enabled,
        units_per_rev=mur,
        total_range=draw(st.one_of(st.just(0), st.integers(1, 2 * physical + 1))),
    )
    span = position_span(geometry, scaling)
    return Scaling(scaling.ccw, scaling.enabled, mur, scaling.total_range, draw(st.integers(0, span - 1)))


@st.composite
def encoder_settings(draw: st.DrawFn, multiturn: bool | None = None) -> EncoderSettings:
    """Geometry, scaling and the signed/unsigned form of one encoder."""
    geometry = draw(geometries(multiturn))
    return EncoderSettings(geometry, draw(scalings(geometry)), signed=draw(st.booleans()))


@st.composite
def dividing_scalings(draw: st.DrawFn, small_mur: bool | None = None) -> tuple[EncoderGeometry, Scaling]:
    """Scaling on with a total range that divides revolutions x MUR (factors drawn: TMR = r1 m1 | r1 r2 m1 m2).

    ``small_mur``: True keeps MUR <= steps per revolution (no value skipped), False forces MUR above it.
    """
    r1, r2 = draw(st.integers(1, 64)), draw(st.integers(1, 64))
    m1, m2 = draw(st.integers(1, 256)), draw(st.integers(1, 256))
    mur = m1 * m2
    if small_mur is None:
        steps = draw(steps_per_rev)
    elif small_mur:
        steps = draw(st.integers(mur, max(mur, 70_000)))
    else:
        assume(mur > 1)
        steps = draw(st.integers(1, mur - 1))
    geometry = EncoderGeometry(steps, r1 * r2)
    total = r1 * m1
    scaling = Scaling(ccw=draw(st.booleans()), enabled=True, units_per_rev=mur, total_range=total,
                      offset=draw(st.integers(0, total - 1)))
    return geometry, scaling


def circular_distance(a: Fraction | int, b: Fraction | int, span: int) -> Fraction:
    """How far apart two values are on a circle of ``span`` units."""
    d = Fraction(a - b) % span
    return min(d, span - d)


# -- position: range and signed form -----------------------------------------------------------


@MANY
@given(encoder_settings(), turns)
def test_position_stays_within_its_limits(cfg: EncoderSettings, angle: float) -> None:
    """Any shaft angle reads 0 .. span-1 unsigned, and the shown value lies within position_limits (650Ah)."""
    ref = EncoderReference(cfg)
    lo, hi = cfg.limits()
    assert 0 <= ref.unsigned_position(angle) < cfg.span
    assert lo <= ref.position(angle) <= hi
    assert hi - lo + 1 == cfg.span


@MANY
@given(st.integers(1, 1 << 32), st.data())
def test_signed_and_unsigned_forms_are_inverses(span: int, data: st.DataObject) -> None:
    """signed_half_range maps 0..span-1 onto the signed limits one-to-one; unsigned_in_span undoes it."""
    lo, hi = position_limits(span, signed=True)
    value = data.draw(st.integers(0, span - 1))
    shown = signed_half_range(value, span)
    assert lo <= shown <= hi
    assert unsigned_in_span(shown, span) == value
    signed_value = data.draw(st.integers(lo, hi))
    assert signed_half_range(unsigned_in_span(signed_value, span), span) == signed_value
    assert position_limits(span, signed=False) == (0, span - 1)


# -- preset --------------------------------------------------------------------------------------


@MANY
@given(encoder_settings(), turns, st.data())
def test_preset_makes_the_position_read_the_preset(cfg: EncoderSettings, angle: float, data: st.DataObject) -> None:
    """After a preset P at a shaft angle, the position there reads P (shown form) and 6509h is in 0..span-1.

    Both code sequences, scaling on and off, singleturn and multiturn, signed and unsigned.
    """
    ref = EncoderReference(cfg)
    lo, hi = cfg.limits()
    preset = data.draw(st.integers(lo, hi), label="preset")
    offset = ref.apply_preset(preset, angle)
    assert 0 <= offset < cfg.span
    assert ref.position(angle) == preset
    shown_lo, shown_hi = ref.settings.limits()
    assert shown_lo <= ref.shown_offset() <= shown_hi


@given(encoder_settings(), turns, turns)
def test_preset_of_the_shown_position_is_idempotent(cfg: EncoderSettings, angle: float, other: float) -> None:
    """Presetting the value the encoder already shows leaves the offset unchanged, at any shaft angle."""
    ref = EncoderReference(cfg)
    for where in (angle, other):
        assert ref.offset_for_preset(ref.position(where), where) == cfg.scaling.offset


@given(encoder_settings(), turns, st.data())
def test_preset_does_not_depend_on_the_previous_offset(cfg: EncoderSettings, angle: float, data: st.DataObject) -> None:
    """The offset a preset produces depends on the shaft and the preset only, not on an earlier preset."""
    lo, hi = cfg.limits()
    first, second = data.draw(st.integers(lo, hi)), data.draw(st.integers(lo, hi))
    fresh = EncoderReference(cfg)
    twice = EncoderReference(cfg)
    twice.apply_preset(first, angle)
    assert twice.apply_preset(second, angle) == fresh.apply_preset(second, angle)


def test_preset_offset_wraps_into_the_range() -> None:
    """preset_offset: the difference modulo the range, never negative."""
    assert preset_offset(0, 10, 4096) == 4086
    assert preset_offset(-1, 0, 4096) == 4095
    assert preset_offset(5, 5, 4096) == 0


# -- code sequence and scaling -----------------------------------------------------------------


@MANY
@given(geometries(), st.booleans(), st.booleans(), st.integers(0, 1 << 31), st.integers(-100_000, 100_000))
def test_unscaled_position_follows_the_shaft_in_the_code_sequence_direction(
        geometry: EncoderGeometry, ccw: bool, bit_without_mur: bool, counts: int, k: int) -> None:
    """Without scaling, +k physical steps change the value by +k (CW) or -k (CCW) modulo the physical range.

    Scaling is off with the bit clear, and also with the bit set but no MUR (6001h = 0).
    """
    scaling = Scaling(ccw=ccw, enabled=bit_without_mur, units_per_rev=0, total_range=12345)
    span = position_span(geometry, scaling)
    assert span == geometry.range
    before = position_value(turns_for_counts(counts, geometry), geometry, scaling)
    after = position_value(turns_for_counts(counts + k, geometry), geometry, scaling)
    assert (after - before) % span == (-k if ccw else k) % span


@MANY
@given(dividing_scalings(), st.integers(0, 1 << 31), st.integers(-100_000, 100_000))
def test_scaled_position_moves_mur_per_revolution(
        setup: tuple[EncoderGeometry, Scaling], counts: int, k: int) -> None:
    """With scaling, +k physical steps change the value by k x MUR / steps (negated CCW), within rounding."""
    geometry, scaling = setup
    span = position_span(geometry, scaling)
    before = counts_value(counts % geometry.range, geometry, scaling)
    after = counts_value((counts + k) % geometry.range, geometry, scaling)
    expected = Fraction((-k if scaling.ccw else k) * scaling.units_per_rev, geometry.steps_per_rev)
    assert circular_distance(after - before, expected, span) < 1


@MANY
@given(dividing_scalings(small_mur=True), st.integers(0, 1 << 31))
def test_dividing_total_range_is_continuous_across_the_physical_wrap(
        setup: tuple[EncoderGeometry, Scaling], counts: int) -> None:
    """TMR dividing revolutions x MUR (MUR <= steps): one count moves the value by 0 or 1 unit, wrap included."""
    geometry, scaling = setup
    span = position_span(geometry, scaling)
    step = -1 if scaling.ccw else 1
    for c in (counts % geometry.range, geometry.range - 1):  # anywhere, and at the physical wrap
        change = (counts_value((c + 1) % geometry.range, geometry, scaling) - counts_value(c, geometry, scaling))
        assert change % span in {0, step % span}


@given(dividing_scalings(small_mur=False), st.integers(0, 1 << 31))
def test_dividing_total_range_with_skipped_values_moves_at_most_ceil_mur_per_step(
        setup: tuple[EncoderGeometry, Scaling], counts: int) -> None:
    """MUR > steps: one count moves the value by at most ceil(MUR / steps) units, wrap included."""
    geometry, scaling = setup
    span = position_span(geometry, scaling)
    most = math.ceil(Fraction(scaling.units_per_rev, geometry.steps_per_rev))
    for c in (counts % geometry.range, geometry.range - 1):
        change = counts_value((c + 1) % geometry.range, geometry, scaling) - counts_value(c, geometry, scaling)
        assert circular_distance(change, 0, span) <= most


@given(st.integers(1, 4096), st.integers(2, 256), st.data())
def test_non_dividing_total_range_jumps_at_the_physical_wrap(steps: int, revs: int, data: st.DataObject) -> None:
    """Documented behaviour (multi-turn): a TMR that does not divide revolutions x MUR makes the value jump at the
    physical wrap (a singleturn range is one revolution whatever 6002h holds).

    CW: from count range-1 to count 0 the value moves by (1 - revolutions x MUR) mod TMR instead of 1
    (CCW: the same jump from count 0 to count 1); CiA 406 asks for a dividing range, the model keeps
    the physical wrap (rule ``wrap``).
    """
    mur = data.draw(st.integers(1, steps))
    physical = revs * mur
    total = data.draw(st.integers(2, 2 * physical + 1).filter(lambda t: physical % t != 0))
    geometry = EncoderGeometry(steps, revs)
    jump = (1 - physical) % total
    assert jump != 1
    for ccw in (False, True):
        scaling = Scaling(ccw=ccw, enabled=True, units_per_rev=mur, total_range=total,
                          offset=data.draw(st.integers(0, total - 1)))
        last, first = (geometry.range - 1, 0) if not ccw else (0, 1)
        change = counts_value(first, geometry, scaling) - counts_value(last, geometry, scaling)
        assert change % total == (jump if not ccw else -jump % total)


@given(geometries(), st.booleans(), st.integers(0, 1 << 31))
def test_total_range_is_ignored_without_scaling(geometry: EncoderGeometry, ccw: bool, counts: int) -> None:
    """Scaling off: the value wraps at the physical range whatever 6002h says."""
    plain = Scaling(ccw=ccw)
    with_tmr = Scaling(ccw=ccw, units_per_rev=3, total_range=7)
    c = counts % geometry.range
    assert counts_value(c, geometry, plain) == counts_value(c, geometry, with_tmr)
    assert position_span(geometry, with_tmr) == geometry.range


@MANY
@given(geometries(), st.integers(-(1 << 40), 1 << 40))
def test_turns_for_counts_lands_on_its_count(geometry: EncoderGeometry, counts: int) -> None:
    """turns_for_counts gives an angle whose physical counts are exactly the ones asked (modulo the range)."""
    assert raw_counts(turns_for_counts(counts, geometry), geometry) == counts % geometry.range


# -- inverse: shaft angle for a position -------------------------------------------------------


@st.composite
def small_encoders(draw: st.DrawFn) -> tuple[EncoderGeometry, Scaling]:
    """Sensors small enough to list every position they can show."""
    geometry = EncoderGeometry(draw(st.integers(1, 32)), draw(st.integers(1, 8)))
    steps, physical_turns = geometry.steps_per_rev, geometry.revolutions
    # half the time MUR above the steps and a TMR shorter than the physical range: values skipped per round
    mur = draw(st.one_of(st.integers(0, 3 * steps), st.integers(steps + 1, 3 * steps)))
    total = draw(st.one_of(st.just(0), st.integers(1, 2 * physical_turns * mur + 1),
                           st.integers(1, max(1, physical_turns * mur - 1))))
    scaling = Scaling(ccw=draw(st.booleans()), enabled=draw(st.booleans()), units_per_rev=mur, total_range=total)
    span = position_span(geometry, scaling)
    return geometry, Scaling(scaling.ccw, scaling.enabled, mur, scaling.total_range, draw(st.integers(0, span - 1)))


@MANY
@given(small_encoders())
def test_counts_for_position_finds_every_position_some_count_shows(setup: tuple[EncoderGeometry, Scaling]) -> None:
    """counts_for_position is the inverse of counts_value wherever a count exists, and None only where none does."""
    geometry, scaling = setup
    shown = {counts_value(c, geometry, scaling) for c in range(geometry.range)}
    for target in range(position_span(geometry, scaling)):
        counts = counts_for_position(target, geometry, scaling)
        if target in shown:
            assert counts is not None, f"position {target} is shown by some count but not found"
            assert 0 <= counts < geometry.range
            assert counts_value(counts, geometry, scaling) == target
        else:
            assert counts is None


@MANY
@given(encoder_settings(), st.data())
def test_turns_for_is_the_inverse_of_the_position(cfg: EncoderSettings, data: st.DataObject) -> None:
    """EncoderReference.turns_for(P) is an angle reading P; None only where scaling skips P (MUR > steps).

    Values a count shows are taken from a random shaft angle (always reachable); any value in the
    limits is reachable unless scaling is on with MUR above the steps or TMR above revolutions x MUR.
    """
    ref = EncoderReference(cfg)
    reached = ref.position(data.draw(turns))
    angle = ref.turns_for(reached)
    assert angle is not None
    assert ref.position(angle) == reached
    lo, hi = cfg.limits()
    target = data.draw(st.integers(lo, hi))
    angle = ref.turns_for(target)
    scaling = cfg.scaling
    dense = not (scaling.enabled and scaling.units_per_rev > 0) or (
        scaling.units_per_rev <= cfg.geometry.steps_per_rev
        and cfg.span <= cfg.geometry.revolutions * scaling.units_per_rev)
    if dense:
        assert angle is not None
    if angle is not None:
        assert ref.position(angle) == target


# -- CAM ------------------------------------------------------------------------------------------

limits = st.integers(-100, 100)
positions = st.integers(-250, 250)
hystereses = st.integers(0, 30)
rules = st.builds(CamRules, low_above_high=st.sampled_from(["wrap", "swap", "refused"]), edges_inclusive=st.booleans())


@st.composite
def cam_channels(draw: st.DrawFn, hysteresis: st.SearchStrategy[int] = hystereses) -> CamChannel:
    """One channel of up to 8 cams, any enable and polarity bits."""
    n = draw(st.integers(1, 8))
    cams = tuple(Cam(draw(limits), draw(limits), draw(hysteresis)) for _ in range(n))
    return CamChannel(enable=draw(st.integers(0, 255)), polarity=draw(st.integers(0, 255)), cams=cams)


@given(cam_channels(st.just(0)), rules, st.lists(positions, min_size=1, max_size=30))
def test_cam_without_hysteresis_is_memoryless(channel: CamChannel, r: CamRules, path: list[int]) -> None:
    """Hysteresis 0: the tracked state equals the window test at every position, whatever the history.

    Bit n is 1 for an enabled cam whose window holds the position, XOR its polarity bit.
    """
    tracker = CamTracker(r)
    for p in path:
        expected = sum(1 << n for n, cam in enumerate(channel.cams)
                       if channel.enabled(n) and inside(p, cam.low, cam.high, r) != bool(channel.polarity >> n & 1))
        assert tracker.update(p, channel) == expected == cam_state(p, channel, r)


@given(cam_channels(), rules, st.lists(positions, min_size=1, max_size=30))
def test_cam_polarity_is_an_xor_and_disabled_cams_read_zero(channel: CamChannel, r: CamRules,
                                                          path: list[int]) -> None:
    """Along any path: polarity flips exactly the enabled cams' bits; disabled cams read 0 whatever the polarity."""
    plain = CamChannel(channel.enable, 0, channel.cams)
    inverted, straight = CamTracker(r), CamTracker(r)
    mask = (1 << len(channel.cams)) - 1
    for p in path:
        state = inverted.update(p, channel)
        assert state ^ straight.update(p, plain) == channel.polarity & channel.enable & mask
        assert state & ~channel.enable == 0


@MANY
@given(limits, limits, hystereses, rules, positions, positions)
def test_active_cam_holds_within_hysteresis_of_its_window(low: int, high: int, h: int, r: CamRules,
                                                          start: int, p: int) -> None:
    """An active cam stays active exactly where some position of its window is within h (any window form).

    For low <= high with inclusive edges that is [low - h, high + h]; the same holds for wrap-around
    windows (rule wrap/refused), swapped windows (rule swap) and exclusive edges.
    """
    assume(inside(start, low, high, r))
    channel = CamChannel(enable=1, polarity=0, cams=(Cam(low, high, h),))
    tracker = CamTracker(r)
    assert tracker.update(start, channel) == 1
    near = any(inside(p + d, low, high, r) for d in range(-h, h + 1))
    assert tracker.update(p, channel) == int(near)


@given(limits, limits, hystereses, rules, st.lists(positions, min_size=1, max_size=30))
def test_inactive_cam_turns_on_only_inside_its_window(low: int, high: int, h: int, r: CamRules,
                                                      path: list[int]) -> None:
    """Along any path, a cam that was inactive becomes active only at a position inside [low, high]."""
    channel = CamChannel(enable=1, polarity=0, cams=(Cam(low, high, h),))
    tracker = CamTracker(r)
    active = False
    for p in path:
        now = tracker.update(p, channel) == 1
        if now and not active:
            assert inside(p, low, high, r)
        active = now


@given(st.integers(-100, 100), st.integers(0, 100), hystereses)
def test_cam_sweep_switches_off_h_beyond_the_edge_in_the_direction_of_travel(low: int, width: int, h: int) -> None:
    """Sweeping up then down by 1: on at low, off at high + h + 1; back down: on at high, off at low - h - 1."""
    high = low + width
    channel = CamChannel(enable=1, polarity=0, cams=(Cam(low, high, h),))
    tracker = CamTracker()
    up = list(range(low - h - 5, high + h + 6))
    down = up[::-1]
    states_up = [tracker.update(p, channel) for p in up]
    states_down = [tracker.update(p, channel) for p in down]

    def switches(path: list[int], states: list[int]) -> list[tuple[int, int]]:
        """(position, new state) wherever the state changed along the path."""
        return [(path[i], states[i]) for i in range(1, len(path)) if states[i] != states[i - 1]]

    assert switches(up, states_up) == [(low, 1), (high + h + 1, 0)]
    assert switches(down, states_down) == [(high, 1), (low - h - 1, 0)]


@MANY
@given(limits, limits, positions)
def test_cam_window_rules(low: int, high: int, p: int) -> None:
    """Edges belong to the window by default; low > high: "wrap" is the complement of (high, low), "swap" the
    window with the limits swapped; exclusive edges drop exactly the limits."""
    default, exclusive = CamRules(), CamRules(edges_inclusive=False)
    swap = CamRules(low_above_high="swap")
    if low <= high:
        assert inside(low, low, high, default)
        assert inside(high, low, high, default)
        assert inside(p, low, high, default) == (low <= p <= high)
        assert inside(p, low, high, exclusive) == (inside(p, low, high, default) and p not in (low, high))
        assert inside(p, low, high, swap) == inside(p, low, high, default)
    else:
        assert inside(p, low, high, default) == (not high < p < low)
        assert inside(p, low, high, exclusive) == (not high <= p <= low)
        assert inside(p, low, high, swap) == inside(p, high, low, default)
        assert inside(p, low, high, CamRules(low_above_high="refused")) == inside(p, low, high, default)


@MANY
@given(limits, st.integers(1, 100), hystereses, st.booleans(), st.lists(positions, min_size=1, max_size=30))
def test_swapped_cam_behaves_like_the_cam_with_swapped_limits(high: int, width: int, h: int, edges: bool,
                                                              path: list[int]) -> None:
    """Rule "swap": a cam with low > high behaves along any path like the cam (high, low), hysteresis included."""
    low = high + width
    swap = CamRules(low_above_high="swap", edges_inclusive=edges)
    given_cam = CamChannel(enable=1, cams=(Cam(low, high, h),))
    swapped = CamChannel(enable=1, cams=(Cam(min(low, high), max(low, high), h),))
    a, b = CamTracker(swap), CamTracker(swap)
    for p in path:
        assert a.update(p, given_cam) == b.update(p, swapped)


def test_cam_history_is_per_channel_and_forgotten() -> None:
    """EncoderReference keeps one history per channel; forget_cam_history starts without one."""
    geometry = EncoderGeometry(4096, 1)
    cam = Cam(100, 200, 20)
    cfg = EncoderSettings(geometry, Scaling(), signed=False,
                          cam_channels=(CamChannel(1, 0, (cam,)), CamChannel(1, 0, (cam,))))
    ref = EncoderReference(cfg)
    assert ref.cam_state(150, 1) == 1
    assert ref.cam_state(210, 1) == 1  # held by the hysteresis
    assert ref.cam_state(210, 2) == 0  # channel 2 never was active
    ref.forget_cam_history()
    assert ref.cam_state(210, 1) == 0


# -- work area ------------------------------------------------------------------------------------


@MANY
@given(st.integers(-(1 << 31), (1 << 31) - 1), st.integers(-(1 << 31), (1 << 31) - 1),
       st.integers(-(1 << 31), (1 << 31) - 1))
def test_work_area_state_is_exactly_one_of_inside_above_below(a: int, b: int, p: int) -> None:
    """6400h: 00h inside [low, high] (limits included), 02h above high, 04h below low, never two at once."""
    low, high = min(a, b), max(a, b)
    state = area_state(p, low, high)
    assert state in {0, ABOVE, BELOW}
    assert (state == 0) == (low <= p <= high)
    assert (state == ABOVE) == (p > high)
    assert (state == BELOW) == (p < low)


# -- speed ------------------------------------------------------------------------------------------

speeds = st.floats(-1_000, 1_000, allow_nan=False, allow_infinity=False)
factors = st.builds(Fraction, st.integers(1, 100), st.integers(1, 100))


@MANY
@given(speeds, st.integers(1, 1 << 16), factors)
def test_speed_sign_follows_the_code_sequence_and_saturates(rps: float, units: int, factor: Fraction) -> None:
    """CCW negates the speed; the value always fits SIGNED16 and sticks at its limits beyond them."""
    cw = speed_value(rps, units, False, factor)
    ccw = speed_value(rps, units, True, factor)
    for value in (cw, ccw):
        assert S16_MIN <= value <= S16_MAX
    if abs(cw) < S16_MAX:
        assert ccw == -cw
    else:
        assert (cw > 0) != (ccw > 0)
        assert abs(ccw) >= S16_MAX
    exact = rps * units * factor
    if abs(exact) <= S16_MAX:
        assert abs(cw - exact) <= Fraction(1, 2) + Fraction(1, 10**6)
    elif exact > 0:
        assert (cw, ccw) == (S16_MAX, S16_MIN)
    else:
        assert (cw, ccw) == (S16_MIN, S16_MAX)


@MANY
@given(speeds, st.integers(1, 4096), st.integers(1, 16), factors)
def test_speed_is_proportional_to_units_and_factor(rps: float, units: int, k: int, factor: Fraction) -> None:
    """k times the units per revolution (or the factor) gives k times the speed, within rounding, unsaturated."""
    one = speed_value(rps, units, False)
    more_units = speed_value(rps, k * units, False)
    scaled = speed_value(rps, units, False, factor)
    assume(abs(one) < S16_MAX)
    if abs(more_units) < S16_MAX:
        assert abs(more_units - k * one) <= Fraction(k + 1, 2) + Fraction(1, 10**6)
    if abs(scaled) < S16_MAX:
        assert abs(scaled - factor * one) <= (factor + 1) / 2 + Fraction(1, 10**6)


@given(geometries(), st.integers(1, 1 << 16), st.booleans(), speeds)
def test_reference_speed_counts_the_units_in_effect(geometry: EncoderGeometry, mur: int, enabled: bool,
                                                   rps: float) -> None:
    """EncoderReference.speed counts MUR per revolution with scaling on, the physical steps with it off."""
    scaling = Scaling(enabled=enabled, units_per_rev=mur)
    ref = EncoderReference(EncoderSettings(geometry, scaling, signed=False))
    units = mur if enabled else geometry.steps_per_rev
    assert ref.speed(rps) == speed_value(rps, units, False)


# -- settings read from objects ------------------------------------------------------------------


def description(*, multiturn: bool = True, scaling: bool = True, signed: bool = False,
                objects: EncoderObjects | None = None, label_steps: int | None = None,
                label_total: int | None = None) -> EncoderDescription:
    """A device description without a profile: CiA 406 objects, one CAM channel of two cams, a work area."""
    return EncoderDescription(
        objects=objects or EncoderObjects(), multiturn=multiturn, signed=signed, scaling=scaling, preset=True,
        cam_channels=1, cams_per_channel=2, cam_rules=CamRules(), cam_low_above_high_documented=False,
        work_area=True, speed=True, speed_scaling_object=0x2106, flags=None,
        label_steps_per_rev=label_steps, label_total_range=label_total,
    )


@given(st.integers(1, 1 << 16), st.integers(1, 1 << 14), st.integers(0, 0xFF), st.integers(0, 1 << 20),
       st.integers(0, 1 << 30), st.integers(-(1 << 20), 1 << 20), st.booleans(), st.booleans(),
       st.integers(1, 1000), st.integers(1, 1000))
def test_read_settings_gives_the_documented_geometry_and_scaling(
        steps: int, revs: int, operating: int, mur: int, tmr: int, offset: int, multiturn: bool,
        has_scaling: bool, num: int, den: int) -> None:
    """6501h/6502h are the geometry (singleturn: 1 revolution), 6000h bit 0 the code sequence, bit 2 scaling
    (where the device has it), 6001h/6002h/6509h as read, the speed factor sub 1 / sub 2 of its object."""
    objects = {
        (od.SINGLE_TURN_RESOLUTION, 0): steps, (od.REVOLUTIONS, 0): revs, (0x6000, 0): operating,
        (0x6001, 0): mur, (0x6002, 0): tmr, (od.OFFSET, 0): offset,
        (od.CAM_ENABLE, 1): 0b11, (od.CAM_POLARITY, 1): 0b10,
        (od.CAM_LOW, 1): 10, (od.CAM_HIGH, 1): 20, (od.CAM_HYSTERESIS, 1): 3,
        (od.CAM_LOW + 1, 1): 30, (od.CAM_HIGH + 1, 1): 40,
        (od.AREA_LOW, 1): -5, (od.AREA_HIGH, 1): 500,
        (0x2106, 1): num, (0x2106, 2): den,
    }
    cfg = read_settings(description(multiturn=multiturn, scaling=has_scaling), lambda i, s: objects.get((i, s)))
    assert cfg.geometry == EncoderGeometry(steps, revs if multiturn else 1)
    assert cfg.scaling == Scaling(ccw=bool(operating & 1), enabled=bool(operating & 4) and has_scaling,
                                  units_per_rev=mur, total_range=tmr, offset=offset)
    assert cfg.cam_channels == (CamChannel(0b11, 0b10, (Cam(10, 20, 3), Cam(30, 40, 0))),)
    assert cfg.areas == ((-5, 500),)
    assert cfg.speed_factor == Fraction(num, den)
    assert cfg.signed is False


@pytest.mark.parametrize(("multiturn", "label_steps", "label_total", "geometry"), [
    (True, None, None, EncoderGeometry(DEFAULT_STEPS_PER_REV, 1)),
    (False, 8192, None, EncoderGeometry(8192, 1)),
    (True, 8192, 8192 * 16, EncoderGeometry(8192, 16)),
])
def test_read_settings_falls_back_where_objects_are_missing(multiturn: bool, label_steps: int | None,
                                                            label_total: int | None,
                                                            geometry: EncoderGeometry) -> None:
    """Absent objects: type-label steps (else the default sensor), revolutions from the label range (else 1),
    scaling off, offset 0, speed factor 1, an explicit offset where 6509h cannot be read."""
    nothing: dict[tuple[int, int], int] = {}
    desc = description(multiturn=multiturn, label_steps=label_steps, label_total=label_total)
    cfg = read_settings(desc, lambda i, s: nothing.get((i, s)))
    assert cfg.geometry == geometry
    assert cfg.scaling == Scaling()
    assert cfg.speed_factor == 1
    assert read_settings(desc, lambda i, s: None, offset=77).scaling.offset == 77


def test_read_settings_of_relocated_objects() -> None:
    """Manufacturer objects (POSITAL-like, no scaling bit): 6501h/6502h/6509h are not read, scaling always applies."""
    objects = EncoderObjects(operating=0x2000, units_per_rev=0x2001, total_range=0x2002, preset=0x2003,
                             position=0x2004, scaling_bit=None)
    values = {(0x2000, 0): 1, (0x2001, 0): 3600, (0x2002, 0): 3600 * 4, (od.SINGLE_TURN_RESOLUTION, 0): 99,
              (od.REVOLUTIONS, 0): 99, (od.OFFSET, 0): 55}
    desc = description(objects=objects, scaling=False, label_steps=4096, label_total=4096 * 8)
    cfg = read_settings(desc, lambda i, s: values.get((i, s)))
    assert cfg.geometry == EncoderGeometry(4096, 8)
    assert cfg.scaling == Scaling(ccw=True, enabled=True, units_per_rev=3600, total_range=3600 * 4, offset=0)
    assert cfg.span == 3600 * 4
