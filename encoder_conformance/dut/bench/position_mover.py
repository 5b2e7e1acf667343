"""Move the reported position where a test needs it: with the shaft where the bench can turn it, else by preset.

``ShaftMover`` turns the shaft (the twin's, a motor plug-in) by the angle the reference model
gives for the distance, and corrects once or twice where scaling rounds; it remembers how far it
turned so the shaft can go back where it was. ``PresetMover`` writes the preset: the position
jumps there without rotation (enough for CAM windows and work-area limits; the tests that need
real rotation, such as the code sequence, skip on a bench without a shaft drive).
"""

from __future__ import annotations

from typing import Protocol

from encoder_conformance.dut.bench.actuator import ReturningShaft, ShaftDrive
from encoder_conformance.dut.bench.encoder_access import EncoderAccess
from encoder_conformance.models.encoder.position import units_per_rev, unsigned_in_span

#: corrections after the first turn (scaling may round a distance to a neighbouring unit)
CORRECTIONS = 4


class PositionMover(Protocol):
    rotates: bool  # True: the shaft really turns (direction of travel, speed)

    def move_to(self, target: int) -> int:
        """Bring the position to ``target`` (as the device shows it); returns the position read then."""
        ...

    def move_by(self, units: int) -> int:
        """Move by ``units`` measuring units (positive: counting up); returns the position read then."""
        ...


class PresetMover:
    """Moves the position by writing the preset (no rotation; changes the offset)."""

    rotates = False

    def __init__(self, access: EncoderAccess) -> None:
        self.access = access

    def move_to(self, target: int) -> int:
        self.access.preset(target)
        return self.access.position()

    def move_by(self, units: int) -> int:
        settings = self.access.settings(functions=False)
        target = settings.shown(unsigned_in_span(self.access.position() + units, settings.span))
        return self.move_to(target)


class ShaftMover:
    """Moves the position by turning the shaft; remembers how far, to turn it back (``go_home``)."""

    rotates = True

    def __init__(self, access: EncoderAccess, drive: ShaftDrive) -> None:
        self.access = access
        self.drive = ReturningShaft(drive)

    def turn_by(self, revolutions: float) -> None:
        self.drive.turn_by(revolutions)

    def move_by(self, units: int) -> int:
        settings = self.access.settings(functions=False)
        per_rev = units_per_rev(settings.geometry, settings.scaling)
        self.turn_by((-units if settings.scaling.ccw else units) / per_rev)
        return self.access.position()

    def move_to(self, target: int) -> int:
        settings = self.access.settings(functions=False)
        span = settings.span
        position = self.access.position()
        for _ in range(1 + CORRECTIONS):
            distance = unsigned_in_span(target - position, span)
            if distance == 0:
                break
            if distance > span // 2:  # the shorter way round
                distance -= span
            position = self.move_by(distance)
        return position

    def go_home(self) -> None:
        """Turn back what this mover turned (the shaft where it was found), speed 0."""
        self.drive.go_back()
