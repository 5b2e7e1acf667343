"""The bench actuator: stimuli a device cannot give itself over the bus (power, an internal error,
a turning shaft), behind one interface with a simulator and a hardware implementation.

A test asks the actuator for a stimulus; where the bench cannot give it, the actuator says why
(``unavailable``) and the test skips with that reason. The simulator implementation drives the
twin's control channel; on hardware, power comes from the configured power switch and the other
stimuli are not available until a bench plug-in provides them: a shaft drive comes from
``--shaft-drive MODULE:FACTORY[=ARGUMENT]`` (``ShaftDrivePlugin``), e.g. a motor controller.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from encoder_conformance.dut.bench.power import BenchPower


class ShaftDrive(Protocol):
    """Moves the encoder's shaft (the simulator's shaft, a motor plug-in)."""

    def turn_by(self, revolutions: float) -> None: ...

    def set_speed(self, revolutions_per_second: float) -> None: ...


@dataclass(frozen=True)
class ShaftDriveConfig:
    """What a shaft-drive plug-in's factory is given: the text after '=' in the option (None without one),
    the device profile's id and the node-id under test."""

    argument: str | None
    profile_id: str
    node_id: int


@dataclass(frozen=True)
class ShaftDrivePlugin:
    """``--shaft-drive MODULE:FACTORY[=ARGUMENT]``: FACTORY(ShaftDriveConfig) returns a ``ShaftDrive`` (with an
    optional ``close()``, called at the end of the run)."""

    spec: str
    factory: Callable[[ShaftDriveConfig], ShaftDrive]
    argument: str | None

    @classmethod
    def load(cls, spec: str) -> ShaftDrivePlugin:
        """Import the factory; ValueError says what is wrong with ``spec`` and how to write it."""
        target, _, argument = spec.partition("=")
        module_name, colon, factory_name = target.partition(":")
        if not colon or not module_name or not factory_name:
            raise ValueError(f"--shaft-drive {spec}: write MODULE:FACTORY[=ARGUMENT], e.g. "
                             "mybench.motor:shaft_drive=/dev/ttyUSB0")
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:
            raise ValueError(f"--shaft-drive {spec}: cannot import {module_name} ({exc}); is it on the Python "
                             "path (run from its folder or install it)?") from None
        factory = getattr(module, factory_name, None)
        if not callable(factory):
            raise ValueError(f"--shaft-drive {spec}: {module_name} has no callable {factory_name}")
        return cls(spec, factory, argument or None)

    def create(self, profile_id: str, node_id: int) -> ShaftDrive:
        drive = self.factory(ShaftDriveConfig(self.argument, profile_id, node_id))
        missing = [name for name in ("turn_by", "set_speed") if not callable(getattr(drive, name, None))]
        if missing:
            raise TypeError(f"--shaft-drive {self.spec}: the factory returned {type(drive).__name__} without "
                            f"{' and '.join(missing)}")
        return drive


class ErrorStimulus(Protocol):
    """Makes the device detect an internal error (and send its EMCY), and makes the cause go away (the device
    then sends the error-reset EMCY 0000h)."""

    def raise_emcy(self, code: int, register_bits: int, info: bytes = b"") -> None: ...

    def clear_emcy(self) -> None: ...


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


def hardware_bench(power: BenchPower | None, shaft: ShaftDrive | None = None) -> BenchActuator:
    """A real device: power where a switch is configured, the shaft where a drive plug-in turns it; no error
    stimulus yet."""
    unavailable = {
        "errors": "no way to make a real device detect an internal error on demand, nor to make its cause go "
                  "away (the simulator provides both; the EMCY tests use the bus triggers where the profile has "
                  "them: a SYNC of the wrong length with 1019h, a heartbeat-consumer time-out with 1016h)",
    }
    if shaft is None:
        unavailable["shaft"] = ("no shaft drive on this bench (--shaft-drive MODULE:FACTORY plugs in a motor; or "
                                "use the simulator)")
    if power is None:
        unavailable["power"] = ("no power switch configured (--power-off-cmd/--power-on-cmd, --power-manual or "
                                "--station)")
    return BenchActuator(power=power, shaft=shaft, unavailable=unavailable)
