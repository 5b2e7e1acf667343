"""Power switches for the tests that switch the device off and on (the bench actuator's power part).

A bench has one of: a shell command pair (a relay board, a lab supply's CLI, a smart plug), an
operator at a prompt, or the simulator's control channel. Tests ask the switch; without one they
skip with the options that would provide it.
"""

from __future__ import annotations

import subprocess
import threading
from collections.abc import Callable
from typing import Protocol

from encoder_conformance.errors import PowerSwitchError

COMMAND_TIMEOUT_S = 30.0
HOW_TO_CONFIGURE = "--power-off-cmd/--power-on-cmd, --power-manual, or a station file with 'power:'"


class PowerSwitch(Protocol):
    description: str
    off_time_s: float

    def off(self) -> None: ...

    def on(self) -> None: ...


class SupplyControl(Protocol):
    """What switches the simulated twin's supply (the simulator's control client)."""

    def power_off(self) -> None: ...

    def power_on(self) -> None: ...


class ShellPowerSwitch:
    """Runs one shell command to switch off and one to switch on (exit status 0 = done)."""

    def __init__(self, off_command: str, on_command: str, off_time_s: float = 1.0) -> None:
        self.off_command = off_command
        self.on_command = on_command
        self.off_time_s = off_time_s
        self.description = f"shell commands (off: {off_command!r}, on: {on_command!r})"

    def off(self) -> None:
        self._run(self.off_command, "--power-off-cmd")

    def on(self) -> None:
        self._run(self.on_command, "--power-on-cmd")

    @staticmethod
    def _run(command: str, option: str) -> None:
        try:
            # a session of its own: a Ctrl-C at the terminal stops the run, not the relay command half-way
            done = subprocess.run(command, shell=True, capture_output=True, text=True, timeout=COMMAND_TIMEOUT_S,
                                  start_new_session=True)
        except subprocess.TimeoutExpired:
            raise PowerSwitchError(f"{option} {command!r} did not finish within {COMMAND_TIMEOUT_S:.0f} s") from None
        if done.returncode != 0:
            output = (done.stderr or done.stdout).strip()[-300:]
            raise PowerSwitchError(f"{option} {command!r} failed with exit status {done.returncode}: {output}")


class ManualPowerSwitch:
    """Asks the operator at the terminal (``prompt`` shows the text and returns once Enter is pressed)."""

    def __init__(self, prompt: Callable[[str], None], off_time_s: float = 0.0) -> None:
        self._prompt = prompt
        self.off_time_s = off_time_s
        self.description = "the operator (manual prompt)"

    def off(self) -> None:
        self._prompt("Switch the device's power OFF, then press Enter")

    def on(self) -> None:
        self._prompt("Switch the device's power ON, then press Enter")


class SimulatorPowerSwitch:
    """The simulated twin's supply, through its control channel."""

    def __init__(self, control: SupplyControl) -> None:
        self._control = control
        self.off_time_s = 0.0
        self.description = "the simulator's control channel"

    def off(self) -> None:
        self._control.power_off()

    def on(self) -> None:
        self._control.power_on()


class BenchPower:
    """A power switch that remembers whether the run left the device off (Ctrl-C between off and on):
    the run's restore switches it on again before anything else."""

    def __init__(self, switch: PowerSwitch) -> None:
        self.switch = switch
        self.left_off = False

    @property
    def description(self) -> str:
        return self.switch.description

    def cycle(self, before_on: Callable[[], object] | None = None) -> None:
        """Off, keep it off for the switch's off time (so the supply really drops), on; ``before_on`` is called
        just before the switch is told to switch on (where a window after the power-on starts:
        dut/bench/power_on.py)."""
        self.left_off = True  # also when 'off' is interrupted half-way: the state is not known then
        self.switch.off()
        if self.switch.off_time_s > 0:
            threading.Event().wait(self.switch.off_time_s)  # a hold time of the stimulus, not a wait for the device
        if before_on is not None:
            before_on()
        self.switch.on()
        self.left_off = False

    def ensure_on(self) -> bool:
        """Switch on if a cycle was cut short; True if it had to."""
        if not self.left_off:
            return False
        self.switch.on()
        self.left_off = False
        return True

