"""CiA 406 position arithmetic: shaft angle -> physical counts -> code sequence -> scaling -> preset offset.

The order of the steps and where the value wraps:

1. physical counts ``floor(turns * steps_per_rev)`` wrap at the physical range (6501h x 6502h);
2. code sequence (6000h bit 0): counter-clockwise counting mirrors the counts in that range;
3. scaling (6000h bit 2 where the device has the bit): ``counts * MUR // steps_per_rev`` (6001h);
4. the preset offset (6509h) is added and the sum wraps at the total measuring range (6002h; on a
   singleturn encoder at one revolution, 6001h).

Where the configured range does not divide the physical one (a number of revolutions that is not a
power of two on most devices), the value jumps at the physical wrap: CiA 406 asks the user to pick
a range that divides it; what a device does otherwise is device-specific (rule ``wrap`` of
``EncoderRules``, our inference, so the suites judge that case as inferred).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace


@dataclass(frozen=True)
class EncoderGeometry:
    """Physical resolution of the sensor (6501h steps per revolution, 6502h revolutions)."""

    steps_per_rev: int
    revolutions: int  # 1 for singleturn

    @property
    def range(self) -> int:
        return self.steps_per_rev * self.revolutions


@dataclass(frozen=True)
class Scaling:
    """The user's settings: 6000h code sequence/scaling bits, 6001h MUR, 6002h TMR, 6509h offset."""

    ccw: bool = False
    enabled: bool = False
    units_per_rev: int = 0
    total_range: int = 0
    offset: int = 0

    def without_offset(self) -> Scaling:
        return replace(self, offset=0)


def raw_counts(turns: float, geometry: EncoderGeometry) -> int:
    """Physical counts for a shaft angle, wrapping at the physical range."""
    return math.floor(turns * geometry.steps_per_rev) % geometry.range


def units_per_rev(geometry: EncoderGeometry, scaling: Scaling) -> int:
    """Measuring units per revolution in effect: 6001h with scaling on, else the physical steps."""
    if scaling.enabled and scaling.units_per_rev > 0:
        return scaling.units_per_rev
    return geometry.steps_per_rev


def position_span(geometry: EncoderGeometry, scaling: Scaling) -> int:
    """Where the position value wraps: the total measuring range (scaled or physical); a singleturn
    encoder's range is one revolution whatever 6002h holds."""
    if scaling.enabled and scaling.units_per_rev > 0:
        if geometry.revolutions == 1:
            return scaling.units_per_rev
        return scaling.total_range or geometry.revolutions * scaling.units_per_rev
    return geometry.range


def counts_value(counts: int, geometry: EncoderGeometry, scaling: Scaling) -> int:
    """The position value for physical counts (0 .. range - 1): code sequence, scaling, offset, wrap."""
    if scaling.ccw:
        counts = (geometry.range - counts) % geometry.range
    if scaling.enabled and scaling.units_per_rev > 0:
        counts = counts * scaling.units_per_rev // geometry.steps_per_rev
    span = position_span(geometry, scaling)
    return (counts + scaling.offset) % span if span else counts + scaling.offset


def position_value(turns: float, geometry: EncoderGeometry, scaling: Scaling) -> int:
    """The value 6004h shows for a shaft angle (unsigned form, 0 .. span - 1)."""
    return counts_value(raw_counts(turns, geometry), geometry, scaling)


def unshifted_position(turns: float, geometry: EncoderGeometry, scaling: Scaling) -> int:
    """Position before the preset offset (for computing a new offset on preset)."""
    return position_value(turns, geometry, scaling.without_offset())


def preset_offset(preset: int, unshifted: int, span: int) -> int:
    """The offset (6509h) that makes the position read ``preset`` where it read ``unshifted`` without offset.

    CiA 406: writing the preset value sets the position to it at the current shaft position; the
    offset is the difference, taken modulo the measuring range (0 .. span - 1).
    """
    return (preset - unshifted) % span if span else preset - unshifted


def signed_half_range(value: int, span: int) -> int:
    """A position in 0 .. span - 1 shown in -span/2 .. span/2 - 1 (two's complement halves)."""
    return value - span if span and value >= (span + 1) // 2 else value


def unsigned_in_span(value: int, span: int) -> int:
    """The inverse of ``signed_half_range``: any position value as 0 .. span - 1."""
    return value % span if span else value


def position_limits(span: int, signed: bool) -> tuple[int, int]:
    """Smallest and largest position value the device can show (650Ah sub 2 / sub 3 by CiA 406)."""
    if signed:
        return -(span // 2), (span + 1) // 2 - 1
    return 0, span - 1


def turns_for_counts(counts: int, geometry: EncoderGeometry) -> float:
    """A shaft angle whose physical counts are ``counts`` (the middle of that step, safe from rounding)."""
    return (counts % geometry.range + 0.5) / geometry.steps_per_rev


def counts_for_position(target: int, geometry: EncoderGeometry, scaling: Scaling) -> int | None:
    """Physical counts at which the position reads ``target`` (unsigned form), or None if no count does.

    Used to move a simulated or motor-driven shaft to a position: the inverse of ``counts_value``
    (scaling may skip values: then None). Where the total measuring range is shorter than the
    physical one, the value comes round once per span: a value scaling skips on one round may be
    shown on a later one, so every round up to the physical range (or to where the pattern of
    scaled values repeats, whichever is first) is searched.
    """
    span = position_span(geometry, scaling)
    wanted = (target - scaling.offset) % span if span else target - scaling.offset
    per_rev = units_per_rev(geometry, scaling)
    scaled = scaling.enabled and scaling.units_per_rev > 0
    steps = geometry.steps_per_rev
    end = geometry.range  # counts beyond which nothing new is shown
    if scaled and span:
        end = min(end, steps * span // math.gcd(per_rev, steps * span))  # the scaled values repeat after this
    unshifted = wanted
    while True:
        guess = -(-unshifted * steps // per_rev) if scaled else unshifted
        if guess >= end or guess < 0:
            return None
        for counts in (guess, guess - 1, guess + 1):
            mirrored = (geometry.range - counts) % geometry.range if scaling.ccw else counts % geometry.range
            if counts_value(mirrored, geometry, scaling) == target % span:
                return mirrored
        if not span:
            return None
        unshifted += span
