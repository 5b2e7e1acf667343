"""Limit-switch flag bits in a process value (quirk effect ``limit_switch_flags``, e.g. FRABA POSITAL).

With the Min switch enabled, its flag bit is 1 while the position is below the Min object;
with the Max switch enabled, its flag bit is 1 while the position is above the Max object.
Strict comparisons; the flags clear when the position is back inside the window.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from encoder_conformance.profile.quirk_effects import LimitSwitchFlags as LimitSwitchParams


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
    def from_params(cls, params: LimitSwitchParams) -> LimitSwitchFlags:
        switches = tuple(
            LimitSwitch(spec.object, spec.enable_bit, spec.flag_bit, below=spec is params.min)
            for spec in (params.min, params.max)
            if spec is not None
        )
        return cls(
            value_object=params.value_object,
            enable_object=params.enable_object,
            position_mask=params.position_mask,
            switches=switches,
            channels=frozenset(params.applies_to),
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
