"""Speed value (6030h) as a function of the shaft speed and the settings.

CiA 406: measuring units per second, signed 16 bit, counting in the direction the code sequence
sets. Devices scale it (WDGA: increments/s x 2106h sub 1 / sub 2, quirk ``speed_scaling_object``).
Saturation at the 16-bit limits is our inference (no manual says what happens beyond them).
"""

from __future__ import annotations

from fractions import Fraction

S16_MIN, S16_MAX = -32768, 32767


def speed_value(revolutions_per_second: float, units_per_rev: int, ccw: bool,
                factor: Fraction = Fraction(1)) -> int:
    """Units per second (negative when counting down), times ``factor``, saturated to SIGNED16."""
    value = revolutions_per_second * units_per_rev * float(factor)
    if ccw:
        value = -value
    return max(S16_MIN, min(S16_MAX, round(value)))
