"""Where a window after a power cycle starts: at the power-on, not before the power went off.

A device owes its boot-up (and, after an LSS change, to show its new node-ID) within its boot-up time after it has
power again. The bench switch's on command takes its own time, and a device that detects the bit rate starts only
at the first frame it hears (``wake_if_silent``): the power came on somewhere in between. A mark taken before the
power-off let the off time use the window up (issue 39: with a 1 s off time the WDGA's 1 s boot-up window had run
out before the device had power). The power-on mark counts frames from just before the on command (a device quick
to boot is seen) and time from after the wake-up (no window is cut short by the switch).
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.dut.bench.power import BenchPower
from encoder_conformance.dut.link.device import DeviceLink, wake_if_silent
from encoder_conformance.dut.link.frames import Mark


def powered_on(before_on: Mark, after_on: Mark) -> Mark:
    """The mark of a power-on that happened between two marks: the first's frames, the second's time."""
    return Mark(before_on.seq, after_on.time)


def switch_off_and_on(dut: DeviceLink, power: BenchPower) -> tuple[Mark, str | None]:
    """Switch the device off and on and wake it if it waits for bus traffic; the power-on mark and the quirk the
    wake-up relied on (None: none needed). A PowerSwitchError is the caller's to judge."""
    before_on: list[Mark] = []
    power.cycle(before_on=lambda: before_on.append(dut.frames.mark()))
    quirk = wake_if_silent(dut)
    return powered_on(before_on[-1], dut.frames.mark()), quirk


def power_cycler(dut: DeviceLink, power: BenchPower) -> Callable[[], Mark]:
    """The power cycle the LSS views take (``LssDevice``, ``LssCustody``): off, on, woken; the power-on mark."""
    return lambda: switch_off_and_on(dut, power)[0]
