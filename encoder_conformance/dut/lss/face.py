"""``dut.lss``: the LSS master on the device's bus (CiA 305: COB-IDs 7E5h/7E4h, the profile's answer window) and the
device's LSS address as it reports it (1018h)."""

from __future__ import annotations

from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.lss.lss_master import LssAddress, LssMaster

IDENTITY = 0x1018  # vendor-ID, product code, revision number, serial number: the LSS address (CiA 305 §4)


class LssFace:
    """LSS access to the device: its address and a master that talks to every node on the bus."""

    def __init__(self, dut: DeviceLink) -> None:
        self._dut = dut

    def address(self) -> LssAddress:
        """The device's LSS address, read from 1018h sub 1-4 by SDO."""
        return LssAddress(*(self._dut.read_uint(IDENTITY, sub) for sub in range(1, 5)))

    def master(self) -> LssMaster:
        """An LSS master on the device's bus, its frames in the device's log, waiting the profile's LSS window
        (an answer that must not come: the device's LSS silence window)."""
        dut = self._dut
        return LssMaster(lambda cob_id, data: dut.network.send_message(cob_id, data), dut.frames,
                         dut.profile.timing.lss_response_ms / 1000, windows=dut.windows)
