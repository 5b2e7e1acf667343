"""Shaft-drive plug-in for a served simulator: ``--shaft-drive tests.sim_shaft_drive:drive=HOST:PORT``.

The bench engineer's motor, played by the simulator's control channel (``encoder-conformance sim --control
HOST:PORT``): the same shape as a motor controller's plug-in (``turn_by``, ``set_speed``, ``close``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from encoder_conformance.sim.process import SimulatorControl, parse_address

if TYPE_CHECKING:
    from encoder_conformance.dut.bench.actuator import ShaftDriveConfig


def drive(config: ShaftDriveConfig) -> SimulatorControl:
    """The simulator's control channel at the address given after ``=``."""
    if not config.argument:
        raise ValueError("give the simulator's control address: --shaft-drive tests.sim_shaft_drive:drive=HOST:PORT")
    return SimulatorControl(parse_address(config.argument))
