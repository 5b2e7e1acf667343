"""Stimuli for TPDO tests: every trigger a device may send a TPDO on (SYNC, a turning shaft)."""

from __future__ import annotations

from typing import Any

from .device import DeviceUnderTest
from .frames import Mark


def pdo_stimulus(dut: DeviceUnderTest, device_control: Any | None, duration_s: float, syncs: int = 10) -> Mark:
    """Turn the shaft (simulator only) and send ``syncs`` SYNCs spread over ``duration_s``; returns a mark before.

    The pacing between SYNCs is an observation window on the frame log (the device's answers are
    what the caller inspects), not a wait for the device.
    """
    if device_control is not None:
        device_control.set_speed(1.0)
    mark = dut.frames.mark()
    for _ in range(syncs):
        dut.send_sync()
        dut.frames.quiet_period(lambda m: False, duration_s / syncs)
    if device_control is not None:
        device_control.set_speed(0.0)
    return mark
