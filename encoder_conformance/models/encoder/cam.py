"""CAM state (6300h) as a function of the position and the cam settings, with hysteresis.

Per cam: a window [low, high] (6310h+n / 6320h+n), a hysteresis h (6330h+n), an enable bit (6301h)
and a polarity bit (6302h). The rules this model follows, and what each rests on:

- an enabled cam is active while the position is inside its window; the state bit is the active
  flag XOR the polarity bit (CiA 406 6300h..6302h);
- a disabled cam's state bit is 0, whatever its polarity (WDGA M §7.5 "only enabled cams can
  change state"; the value 0 is our inference);
- the window edges belong to the window (inferred from the WDGA example: CAM1 0..2048, CAM2
  2049..4095);
- hysteresis: an active cam stays active until the position leaves [low - h, high + h]; an inactive
  cam becomes active when it enters [low, high]. So the switch-off point lies h beyond the edge in
  the direction of travel, the switch-on point at the edge (CiA 406 names the hysteresis of the
  switching points without the detail; holding past the edge when leaving is common to every
  reading we know, the switch-on point is our inference);
- a low limit above the high limit: a wrap-around window (active at or above low, or at or below
  high), unless a device refuses such limits (quirk ``cam_low_below_high``) or swaps them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

LowAboveHigh = Literal["wrap", "swap", "refused"]


@dataclass(frozen=True)
class Cam:
    low: int = 0
    high: int = 0
    hysteresis: int = 0


@dataclass(frozen=True)
class CamRules:
    """What a device does where CiA 406 leaves the choice (from its profile)."""

    low_above_high: LowAboveHigh = "wrap"
    edges_inclusive: bool = True


def inside(position: int, low: int, high: int, rules: CamRules) -> bool:
    """Is ``position`` inside the window [low, high] (a wrap-around or swapped window if low > high)?"""
    if low > high and rules.low_above_high == "swap":
        low, high = high, low
    if low <= high:
        if rules.edges_inclusive:
            return low <= position <= high
        return low < position < high
    if rules.edges_inclusive:  # wrap-around: from low up to the end of the range, and from its start up to high
        return position >= low or position <= high
    return position > low or position < high


def cam_active(position: int, cam: Cam, was_active: bool, rules: CamRules) -> bool:
    """The cam's own state (before polarity) after the position reached ``position``.

    The hysteresis widens the window the limits stand for: a swapped window after the swap, both
    parts of a wrap-around window (which may meet: then the active cam holds everywhere).
    """
    if not was_active or cam.hysteresis <= 0:
        return inside(position, cam.low, cam.high, rules)
    low, high, h = cam.low, cam.high, cam.hysteresis
    if low > high and rules.low_above_high == "swap":
        low, high = high, low
    if low <= high:
        return inside(position, low - h, high + h, rules)
    if rules.edges_inclusive:
        return position >= low - h or position <= high + h
    return position > low - h or position < high + h


@dataclass(frozen=True)
class CamChannel:
    """The settings of one CAM channel (one sub-index of 6301h/6302h and of the limit objects)."""

    enable: int = 0
    polarity: int = 0
    cams: tuple[Cam, ...] = ()

    def enabled(self, cam: int) -> bool:
        return bool(self.enable >> cam & 1)


@dataclass
class CamTracker:
    """The remembered active flags of one channel (hysteresis needs the previous state)."""

    rules: CamRules = field(default_factory=CamRules)
    active: list[bool] = field(default_factory=list)

    def update(self, position: int, channel: CamChannel) -> int:
        """The state byte (6300h sub n) after the position reached ``position``."""
        if len(self.active) != len(channel.cams):
            self.active = [False] * len(channel.cams)
        state = 0
        for number, cam in enumerate(channel.cams):
            if not channel.enabled(number):
                self.active[number] = False
                continue
            self.active[number] = cam_active(position, cam, self.active[number], self.rules)
            if self.active[number] != bool(channel.polarity >> number & 1):
                state |= 1 << number
        return state

    def forget(self) -> None:
        """Start without history (power-on, reset node)."""
        self.active = []


def cam_state(position: int, channel: CamChannel, rules: CamRules) -> int:
    """The state byte for a position reached from outside every window (no hysteresis history)."""
    return CamTracker(rules).update(position, channel)
