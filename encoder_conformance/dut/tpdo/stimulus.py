"""Stimuli for TPDO tests: every trigger a device may send a TPDO on (SYNC, a turning shaft)."""

from __future__ import annotations

from collections.abc import Callable

import can

from encoder_conformance.dut.bench.actuator import ShaftDrive
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark

SYNC_SPACING_S = 0.01  # 100 SYNCs per second: a usual bus cycle
TURN_PER_SYNC = 0.01  # revolutions the shaft turns before each SYNC (1 rev/s at the SYNC spacing)


def pdo_stimulus(dut: DeviceLink, shaft: ShaftDrive | None, syncs: int = 10,
                 until: Callable[[can.Message], bool] | None = None) -> Mark:
    """Turn the shaft (where the bench can) a little before each of ``syncs`` SYNCs, SYNC_SPACING_S apart,
    then watch the device's PDO silence window after the last one; returns a mark before the first SYNC.
    The shaft is turned back by the same angle at the end, so the position the device was found at
    stays a valid reference (devices without an offset object are given back by their position at rest).

    Each pause is an observation window on the frame log (the device's answers are what the caller
    inspects), not a wait for the device: the SYNC spacing is the bus cycle the stimulus paces, and after the
    last SYNC the PDO silence window in which a TPDO that must not come would show. With ``until`` (a test that
    expects TPDOs), the stimulus ends at the first frame it matches, waited for up to the PDO answer window after
    the last SYNC (a frame the device owes: never a silence window).
    """
    turned = 0.0
    mark = dut.frames.mark()
    try:
        for _ in range(syncs):
            if shaft is not None:
                shaft.turn_by(TURN_PER_SYNC)
                turned += TURN_PER_SYNC
            dut.send_sync()
            if until is not None and dut.frames.wait_for(until, SYNC_SPACING_S, mark) is not None:
                return mark
            if until is None:
                dut.frames.quiet_period(lambda m: False, SYNC_SPACING_S)
        if until is None:
            dut.frames.quiet_period(lambda m: False, dut.pdo_silence_s)
        else:
            dut.frames.wait_for(until, dut.pdo_answer_s, mark)
    finally:
        if shaft is not None and turned:
            shaft.turn_by(-turned)
    return mark
