"""The encoder function of the independent device, written from CiA 406 and the WDGA manual alone.

Nothing here comes from ``encoder_conformance`` (its model or its twin): the point of this device is to
check the suites against a second reading of the texts. What each rule rests on:

- position (6004h): the sensor counts 6501h steps per revolution over a number of physical revolutions
  (WDGA fact sheet §11.2: 2^32 units at 16384 steps on 32-bit units, i.e. 2^18 revolutions, although
  6502h shows FFFFh); the code sequence (6000h bit 0, M T 8.61) decides which turning direction counts up,
  so counter-clockwise counting mirrors the sensor's count; with scaling on (6000h bit 2) the count is
  converted to 6001h measuring units per revolution and the value wraps at the total measuring range
  6002h (M §8.6; a singleturn device wraps after one revolution); with scaling off the physical
  resolution is used;
- preset (6003h): "the encoder outputs P at the current shaft position" (M §11.3); the difference
  between P and the value shown without an offset is the offset 6509h, and every later value is the
  unshifted value plus that offset, modulo the measuring range;
- CAM (6300h-6337h, M §7.5, §12): an enabled cam is active while the position lies within its low and
  high limit (both limits included: the manual's example CAM1 0..2048 / CAM2 2049..4095 leaves no
  gap); its state bit is that, inverted where its polarity bit is set; a disabled cam cannot change
  state and reads 0; the hysteresis widens the window by its width on both sides for a cam that is
  active, so leaving the window switches it off only that far past the edge; entering switches it on
  at the edge;
- work area (6400h-6402h, fact sheet §11.6): 00h inside the limits (included), 02h above the high
  limit, 04h below the low limit;
- speed (6030h sub 1, M §8.9): units per second times 2106h sub 1 / sub 2, negative when the shaft
  turns against the counting direction, limited to SIGNED16 (the device shows the speed the drive set
  at once: its 1000 ms integration time 2105h sub 2 is not modelled).

``breaks`` selects a deliberate fault (one at a time on the command line) so the suites can show they
catch it: ``direction`` (the code-sequence bit is shown but ignored), ``preset`` (the preset value is
taken as the offset), ``cam-polarity`` (the polarity bits are ignored), ``cam-hysteresis`` (cams switch
off at the window edge, whatever the hysteresis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

BREAKS = ("direction", "preset", "cam-polarity", "cam-hysteresis")
CAMS = 8
S16_LIMIT = 32767

AREA_INSIDE, AREA_ABOVE, AREA_BELOW = 0x00, 0x02, 0x04


@dataclass(frozen=True)
class Sensor:
    """What the hardware counts: steps per revolution (6501h) and distinguishable revolutions."""

    steps_per_rev: int
    revolutions: int

    @property
    def counts(self) -> int:
        return self.steps_per_rev * self.revolutions

    def count(self, turns: float) -> int:
        """The sensor's count for a shaft angle (clockwise revolutions), wrapping at its end."""
        return math.floor(turns * self.steps_per_rev) % self.counts


@dataclass(frozen=True)
class Units:
    """The user's settings the position depends on (6000h, 6001h, 6002h)."""

    operating: int
    units_per_rev: int
    total_range: int
    multiturn: bool
    breaks: frozenset[str] = frozenset()

    @property
    def counts_down_clockwise(self) -> bool:
        return bool(self.operating & 0x01) and "direction" not in self.breaks

    @property
    def scaled(self) -> bool:
        return bool(self.operating & 0x04)

    def per_rev(self, sensor: Sensor) -> int:
        return self.units_per_rev if self.scaled else sensor.steps_per_rev

    def measuring_range(self, sensor: Sensor) -> int:
        """Where the position value wraps (the number of distinct values)."""
        if not self.scaled:
            return sensor.counts if self.multiturn else sensor.steps_per_rev
        if not self.multiturn:
            return self.units_per_rev
        return self.total_range or sensor.counts  # 0: the whole sensor range (WDGA "32-bit device", M §8.6)


def value_without_offset(turns: float, sensor: Sensor, units: Units) -> int:
    """The position the encoder would show with offset 0."""
    count = sensor.count(turns)
    if units.counts_down_clockwise:
        count = (sensor.counts - count) % sensor.counts
    if units.scaled:
        count = count * units.units_per_rev // sensor.steps_per_rev
    return count % units.measuring_range(sensor)


def shown_position(turns: float, sensor: Sensor, units: Units, offset: int) -> int:
    """6004h: the value without offset plus the preset offset, within the measuring range."""
    return (value_without_offset(turns, sensor, units) + offset) % units.measuring_range(sensor)


def offset_for_preset(preset: int, turns: float, sensor: Sensor, units: Units) -> int:
    """6509h after writing ``preset`` to 6003h at shaft angle ``turns`` (0 .. range - 1)."""
    if "preset" in units.breaks:
        return preset  # the fault: the preset value taken as the offset itself
    return (preset - value_without_offset(turns, sensor, units)) % units.measuring_range(sensor)


def speed_value(revolutions_per_second: float, sensor: Sensor, units: Units, multiplier: int, divisor: int) -> int:
    """6030h sub 1 for a shaft turning at ``revolutions_per_second`` (clockwise positive)."""
    value = revolutions_per_second * units.per_rev(sensor) * multiplier / (divisor or 1)
    if units.counts_down_clockwise:
        value = -value
    return max(-S16_LIMIT - 1, min(S16_LIMIT, round(value)))


@dataclass(frozen=True)
class CamSettings:
    """One CAM channel: 6301h enable, 6302h polarity, limits 6310h+n / 6320h+n, hysteresis 6330h+n."""

    enable: int
    polarity: int
    lows: tuple[int, ...]
    highs: tuple[int, ...]
    hysteresis: tuple[int, ...]


@dataclass
class CamSwitch:
    """The cams of one channel; remembers which are active (the hysteresis depends on it)."""

    breaks: frozenset[str] = frozenset()
    active: list[bool] = field(default_factory=lambda: [False] * CAMS)

    def update(self, position: int, cams: CamSettings) -> int:
        """The state byte 6300h after the position reached ``position``."""
        state = 0
        for n in range(CAMS):
            if not cams.enable >> n & 1:
                self.active[n] = False
                continue
            low, high = cams.lows[n], cams.highs[n]
            band = 0 if "cam-hysteresis" in self.breaks else cams.hysteresis[n]
            if self.active[n]:
                self.active[n] = low - band <= position <= high + band
            else:
                self.active[n] = low <= position <= high
            inverted = bool(cams.polarity >> n & 1) and "cam-polarity" not in self.breaks
            if self.active[n] != inverted:
                state |= 1 << n
        return state

    def forget(self) -> None:
        """Power-on / reset: no cam is active until the position is evaluated."""
        self.active = [False] * CAMS


def area_state(position: int, low: int, high: int) -> int:
    """6400h sub 1: inside the limits (included), above the high limit, below the low limit."""
    if position > high:
        return AREA_ABOVE
    if position < low:
        return AREA_BELOW
    return AREA_INSIDE
