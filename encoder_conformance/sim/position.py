"""CiA 406 position arithmetic: raw counts -> code sequence -> scaling -> preset offset."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class EncoderGeometry:
    """Physical resolution of the sensor."""

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


def raw_counts(turns: float, geometry: EncoderGeometry) -> int:
    """Physical counts for a shaft angle, wrapping at the physical range."""
    return math.floor(turns * geometry.steps_per_rev) % geometry.range


def position_span(geometry: EncoderGeometry, scaling: Scaling) -> int:
    """Where the position value wraps: the total measuring range (scaled or physical)."""
    if scaling.enabled and scaling.units_per_rev > 0:
        return scaling.total_range or geometry.revolutions * scaling.units_per_rev
    return geometry.range


def position_value(turns: float, geometry: EncoderGeometry, scaling: Scaling) -> int:
    """The value 6004h shows for a shaft angle (without the preset offset if none is set)."""
    counts = raw_counts(turns, geometry)
    if scaling.ccw:
        counts = (geometry.range - counts) % geometry.range
    if scaling.enabled and scaling.units_per_rev > 0:
        counts = counts * scaling.units_per_rev // geometry.steps_per_rev
    span = position_span(geometry, scaling)
    return (counts + scaling.offset) % span if span else counts + scaling.offset


def signed_half_range(value: int, span: int) -> int:
    """A position in 0 .. span - 1 shown in -span/2 .. span/2 - 1 (two's complement halves)."""
    return value - span if span and value >= (span + 1) // 2 else value


def unshifted_position(turns: float, geometry: EncoderGeometry, scaling: Scaling) -> int:
    """Position before the preset offset (for computing a new offset on preset)."""
    return position_value(turns, geometry, Scaling(scaling.ccw, scaling.enabled, scaling.units_per_rev,
                                                   scaling.total_range, 0))
