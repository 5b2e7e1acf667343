"""``dut.emcy``: where the device sends its emergencies (1014h) and the ways to make it send one."""

from __future__ import annotations

from encoder_conformance.dut.bench.actuator import BenchActuator
from encoder_conformance.dut.emcy.emcy_trigger import EmcyCobId, EmcyTrigger, Write, choose_trigger
from encoder_conformance.dut.link.device import DeviceLink


class EmcyFace:
    """The device's EMCY producer."""

    def __init__(self, dut: DeviceLink) -> None:
        self._dut = dut

    def cob_id(self) -> EmcyCobId:
        """Its COB-ID as the device has it now (None while 1014h bit 31 is set); ``matches`` is its frames."""
        return EmcyCobId.of(self._dut)

    def trigger(self, bench: BenchActuator, write: Write, repeatable: bool = False,
                clears: bool = False) -> EmcyTrigger | str:
        """The first trigger this bench and device offer that does what the test needs; else why there is none."""
        return choose_trigger(self._dut, bench, write, repeatable, clears)
