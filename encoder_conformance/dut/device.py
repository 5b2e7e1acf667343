"""The device under test as the suites see it: the link (SDO, raw frames, the waits each owes, liveness;
``link/device.py``) and one face per protocol, as canopen's ``RemoteNode`` has ``node.sdo``, ``node.nmt`` and
``node.tpdo[n]``: ``dut.sdo``, ``dut.nmt`` (commands, and states reached by ``transition``), ``dut.lss``,
``dut.emcy``, ``dut.tpdo[n]``, ``dut.store`` and ``dut.custody``."""

from __future__ import annotations

import canopen

from encoder_conformance.dut.custody.face import CustodyFace
from encoder_conformance.dut.emcy.face import EmcyFace
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.lss.face import LssFace
from encoder_conformance.dut.nmt.face import NmtFace
from encoder_conformance.dut.sdo.face import SdoFace
from encoder_conformance.dut.store.face import StoreFace
from encoder_conformance.dut.tpdo.face import Tpdos
from encoder_conformance.profile.schema import DeviceProfile


class DeviceUnderTest(DeviceLink):
    """A CANopen node on a bus, with waits that take their limits from the profile, and a face per protocol."""

    def __init__(self, network: canopen.Network, frames: FrameLog, profile: DeviceProfile, node_id: int) -> None:
        super().__init__(network, frames, profile, node_id)
        self.sdo = SdoFace(self)
        self.nmt = NmtFace(self)
        self.lss = LssFace(self)
        self.emcy = EmcyFace(self)
        self.tpdo = Tpdos(self)
        self.store = StoreFace(self)
        self.custody = CustodyFace(self)
