"""The bench actuator: stimuli a device cannot give itself over the bus (power, an internal error,
a turning shaft), behind one interface with a simulator and a hardware implementation.

A test asks the actuator for a stimulus; where the bench cannot give it, the actuator says why
(``unavailable``) and the test skips with that reason. The simulator implementation drives the
twin's control channel; on hardware, power comes from the configured power switch and the other
stimuli are not available until a bench plug-in provides them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

from .power import BenchPower


class ShaftDrive(Protocol):
    """Moves the encoder's shaft (the simulator's shaft, a motor plug-in)."""

    def turn_by(self, revolutions: float) -> None: ...

    def set_speed(self, revolutions_per_second: float) -> None: ...


class ErrorStimulus(Protocol):
    """Makes the device detect an internal error (and send its EMCY)."""

    def raise_emcy(self, code: int, register_bits: int, info: bytes = b"") -> None: ...


class SimulatorControls(ShaftDrive, ErrorStimulus, Protocol):
    """What the simulator's control channel offers (``sim_process.SimulatorControl`` and the in-process form)."""

    def power_off(self) -> None: ...

    def power_on(self) -> None: ...


class ReturningShaft:
    """A shaft drive that remembers how far a test turned it and turns it back afterwards, so the angle the
    device was found at stays its reference (a constant speed is not followed: set it back to 0)."""

    def __init__(self, drive: ShaftDrive) -> None:
        self.drive = drive
        self.turned = 0.0

    def turn_by(self, revolutions: float) -> None:
        self.drive.turn_by(revolutions)
        self.turned += revolutions

    def set_speed(self, revolutions_per_second: float) -> None:
        self.drive.set_speed(revolutions_per_second)

    def go_back(self) -> None:
        self.drive.set_speed(0.0)
        if self.turned:
            self.drive.turn_by(-self.turned)
            self.turned = 0.0


@dataclass
class BenchActuator:
    """The stimuli of one bench; None where the bench has none, with the reason in ``unavailable``."""

    power: BenchPower | None = None
    shaft: ShaftDrive | None = None
    errors: ErrorStimulus | None = None
    unavailable: dict[str, str] = field(default_factory=dict)

    def why_not(self, stimulus: str) -> str:
        """Why the bench cannot give ``stimulus`` ("power", "shaft", "errors")."""
        return self.unavailable.get(stimulus, f"this bench has no {stimulus} stimulus")


def simulator_bench(control: SimulatorControls, power: BenchPower | None) -> BenchActuator:
    """Every stimulus, through the twin's control channel."""
    return BenchActuator(power=power, shaft=control, errors=control)


def hardware_bench(power: BenchPower | None) -> BenchActuator:
    """A real device: power where a switch is configured; no shaft drive or error stimulus yet."""
    unavailable = {
        "shaft": "no shaft drive on this bench (turn the shaft by hand during the test, or use the simulator)",
        "errors": "no way to make a real device detect an internal error on demand (the simulator provides one)",
    }
    if power is None:
        unavailable["power"] = ("no power switch configured (--power-off-cmd/--power-on-cmd, --power-manual or "
                                "--station)")
    return BenchActuator(power=power, unavailable=unavailable)
