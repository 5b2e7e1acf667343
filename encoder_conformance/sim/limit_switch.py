"""Limit-switch flag bits in a process value (quirk effect ``limit_switch_flags``, e.g. FRABA POSITAL).

With the Min switch enabled, its flag bit is 1 while the position is below the Min object;
with the Max switch enabled, its flag bit is 1 while the position is above the Max object.
Strict comparisons; the flags clear when the position is back inside the window.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class LimitSwitch:
    limit_object: int
    enable_bit: int
    flag_bit: int
    below: bool  # True: flag when position < limit (Min); False: when position > limit (Max)


@dataclass(frozen=True)
class LimitSwitchFlags:
    """Which object carries the flags, where they are enabled, and on which channels they show."""

    value_object: int
    enable_object: int
    position_mask: int
    switches: tuple[LimitSwitch, ...]
    channels: frozenset[str]  # "tpdo", "sdo"

    @classmethod
    def from_params(cls, params: dict[str, Any]) -> LimitSwitchFlags:
        switches = tuple(
            LimitSwitch(int(spec["object"]), int(spec["enable_bit"]), int(spec["flag_bit"]), below=name == "min")
            for name in ("min", "max")
            if (spec := params.get(name))
        )
        return cls(
            value_object=int(params["value_object"]),
            enable_object=int(params["enable_object"]),
            position_mask=int(params.get("position_mask", 0xFFFFFFFF)),
            switches=switches,
            channels=frozenset(str(c) for c in params.get("applies_to", ["tpdo", "sdo"])),
        )

    def apply(self, position: int, read: Callable[[int, int], int | None]) -> int:
        """The process value: the masked position plus the flags of the enabled switches."""
        value = position & self.position_mask
        enabled = read(self.enable_object, 0) or 0
        for switch in self.switches:
            if not enabled >> switch.enable_bit & 1:
                continue
            limit = read(switch.limit_object, 0) or 0
            if (position < limit) if switch.below else (position > limit):
                value |= 1 << switch.flag_bit
        return value
