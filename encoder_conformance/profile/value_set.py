"""Sets of integers as profiles declare them: ``allowed: "0..4, 6..9"`` or ``"0, 10..65535"``.

A ValueSet is a sorted tuple of disjoint, non-adjacent inclusive ranges. ``parse`` reads the
profile text (comma-separated integers and ``a..b`` ranges, decimal or 0x hex, negatives
allowed); its errors name the text and the bad part. ``probes`` gives the values a
conformance test writes to see that the device refuses what lies outside the set.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

_INTEGER = re.compile(r"^([+-]?)(0[xX][0-9A-Fa-f]+|[0-9]+)$")


def _integer(token: str, text: str) -> int:
    match = _INTEGER.match(token.strip())
    if not match:
        raise ValueError(f"allowed {text!r}: {token.strip()!r} is not an integer")
    sign, digits = match.groups()
    value = int(digits, 16) if digits[:2].lower() == "0x" else int(digits, 10)
    return -value if sign == "-" else value


def _merged(ranges: Iterable[tuple[int, int]]) -> tuple[tuple[int, int], ...]:
    """Sort and join overlapping or adjacent ranges; drop empty ones (start > end)."""
    result: list[tuple[int, int]] = []
    for start, end in sorted(r for r in ranges if r[0] <= r[1]):
        if result and start <= result[-1][1] + 1:
            result[-1] = (result[-1][0], max(result[-1][1], end))
        else:
            result.append((start, end))
    return tuple(result)


@dataclass(frozen=True)
class ValueSet:
    """A finite set of integers as sorted, disjoint, non-adjacent inclusive ranges."""

    ranges: tuple[tuple[int, int], ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "ranges", _merged(self.ranges))

    # -- construction --------------------------------------------------------------------
    @classmethod
    def parse(cls, text: str) -> ValueSet:
        """``"0..4, 6..9"`` -> {0..4, 6..9}. Raises ValueError naming ``text`` and the bad part."""
        if not isinstance(text, str) or not text.strip():
            raise ValueError(f"allowed {text!r}: write a text of integers and a..b ranges separated by commas, "
                             "e.g. \"0..4, 6..9\"")
        ranges = []
        for item in text.split(","):
            if not item.strip():
                raise ValueError(f"allowed {text!r}: empty item between commas")
            if ".." in item:
                low_text, _, high_text = item.partition("..")
                low, high = _integer(low_text, text), _integer(high_text, text)
                if low > high:
                    raise ValueError(f"allowed {text!r}: range {item.strip()!r} is empty (start above end)")
            else:
                low = high = _integer(item, text)
            ranges.append((low, high))
        return cls(tuple(ranges))

    @classmethod
    def span(cls, low: int, high: int) -> ValueSet:
        """All integers low..high (empty if low > high)."""
        return cls(((low, high),))

    # -- queries -------------------------------------------------------------------------
    def __contains__(self, value: object) -> bool:
        return isinstance(value, int) and any(start <= value <= end for start, end in self.ranges)

    def __iter__(self) -> Iterator[tuple[int, int]]:
        return iter(self.ranges)

    def __bool__(self) -> bool:
        return bool(self.ranges)

    def __str__(self) -> str:
        return ", ".join(str(a) if a == b else f"{a}..{b}" for a, b in self.ranges)

    @property
    def minimum(self) -> int | None:
        return self.ranges[0][0] if self.ranges else None

    @property
    def maximum(self) -> int | None:
        return self.ranges[-1][1] if self.ranges else None

    def intersection(self, other: ValueSet) -> ValueSet:
        pieces = [
            (max(a, c), min(b, d)) for a, b in self.ranges for c, d in other.ranges if max(a, c) <= min(b, d)
        ]
        return ValueSet(tuple(pieces))

    def __and__(self, other: ValueSet) -> ValueSet:
        return self.intersection(other)

    def issubset(self, other: ValueSet) -> bool:
        return self.intersection(other) == self

    def outside(self, other: ValueSet) -> ValueSet:
        """The values of this set that ``other`` lacks."""
        gaps: list[tuple[int | None, int | None]] = []
        cursor: int | None = None
        for start, end in other.ranges:
            gaps.append((cursor, start - 1))
            cursor = end + 1
        gaps.append((cursor, None))
        pieces = []
        for low, high in gaps:
            for a, b in self.ranges:
                lo = a if low is None else max(a, low)
                hi = b if high is None else min(b, high)
                if lo <= hi:
                    pieces.append((lo, hi))
        return ValueSet(tuple(pieces))

    def probes(self, low: int, high: int) -> list[int]:
        """Values just below each range start and just above each range end, within low..high.

        Each lies outside the set (the ranges are disjoint and not adjacent), so a device that
        enforces the set must refuse it. Empty when the set covers all of low..high.
        """
        values: set[int] = set()
        for start, end in self.ranges:
            values.update(v for v in (start - 1, end + 1) if low <= v <= high)
        return sorted(values)
