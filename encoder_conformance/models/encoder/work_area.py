"""Work area state (6400h) as a function of the position and the limits 6401h/6402h.

CiA 406 6400h: bit 0 out of range (outside 650Ah min..max), bit 1 range overflow (position above
the work area high limit), bit 2 range underflow (below the low limit); the WDGA manual (T 6.9)
gives the same values (00h inside, 02h above, 04h below). Whether the limits belong to the work
area is not written anywhere we know: the limits are inside (our inference).
"""

from __future__ import annotations

ABOVE = 0x02
BELOW = 0x04


def area_state(position: int, low: int, high: int) -> int:
    """The area state byte: 00h inside [low, high], 02h above high, 04h below low."""
    if position > high:
        return ABOVE
    if position < low:
        return BELOW
    return 0
