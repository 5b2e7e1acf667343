"""Quirk ``cam_low_below_high`` (WDGA): a CAM low limit is accepted only below the same cam's high limit.

A write to a low limit 6310h+n sub k is compared with the high limit 6320h+n sub k as it stands
then; a low limit at or above it is refused with the quirk's abort code (so the high limit has to
be written first, and a wrap-around window cannot be set). The high limit itself is not checked.
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.models.encoder import objects as od
from encoder_conformance.profile.quirk_effects import CamLowBelowHigh
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.sdo_server import SdoAbort

#: an integer entry as its data type reads it (SIGNED types negative), None where absent
Reader = Callable[[int, int], "int | None"]
#: a written integer as its entry's data type reads it
AsSigned = Callable[[Key, int], int]


class CamLowLimitGate:
    """A write gate: refuses a low limit at or above the same cam's current high limit."""

    def __init__(self, params: CamLowBelowHigh, read: Reader, as_signed: AsSigned, cams_per_channel: int) -> None:
        self._abort = int(params.abort_code)
        self._read = read
        self._as_signed = as_signed
        self._cams = cams_per_channel

    def register(self, hooks: NodeHooks) -> None:
        hooks.gates.append(self.gate)

    def gate(self, key: Key, value: Value) -> None:
        index, sub = key
        cam = index - od.CAM_LOW
        if not 0 <= cam < self._cams or sub < 1 or not isinstance(value, int):
            return
        _, high_object, _ = od.cam_limit_objects(cam)
        high = self._read(high_object, sub)
        if high is not None and self.refuses(self._as_signed(key, value), high):
            raise SdoAbort(self._abort)

    def refuses(self, low: int, high: int) -> bool:
        """Is the low limit ``low`` refused while the high limit is ``high``?"""
        return low >= high


@breaks(CamLowLimitGate, "cam_low_order_ignored")
class CamLowOrderIgnored(CamLowLimitGate):
    def refuses(self, low: int, high: int) -> bool:
        return False
