"""One TPDO of the device, as canopen's ``node.tpdo[n]``: its parameters' indices, its COB-ID and CAN-ID as the
device has them now, the predicate of its frames and the windows they are waited and watched for."""

from __future__ import annotations

from encoder_conformance.cia.cia301 import PDO_MAPPING_OFFSET, TPDO_COMMUNICATION, can_id_of
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Predicate, received_on

#: TPDOs 1..512 (communication parameters 1800h..19FFh, CiA 301 §7.5.2.37)
TPDO_COUNT = len(TPDO_COMMUNICATION)


class TpdoParameters:
    """What a TPDO owns, given its device (``dut``) and communication parameter (``comm``, 18xxh)."""

    dut: DeviceLink
    comm: int

    @property
    def mapping_index(self) -> int:
        """Its mapping parameter (1Axxh)."""
        return self.comm + PDO_MAPPING_OFFSET

    def cob_id(self) -> int:
        """Sub 1 (COB-ID) as the device has it now."""
        return self.dut.read_uint(self.comm, 1)

    def can_id(self) -> int:
        """The CAN-ID it is sent on, from sub 1 read now."""
        return can_id_of(self.cob_id())

    def frames(self, can_id: int | None = None) -> Predicate:
        """Its frames: data frames the device sends on ``can_id`` (default its CAN-ID, read now)."""
        return received_on(self.can_id() if can_id is None else can_id)

    @property
    def answer_s(self) -> float:
        """How long a TPDO the device owes (after a SYNC, an RTR) is waited for."""
        return self.dut.pdo_answer_s

    @property
    def silence_s(self) -> float:
        """How long to watch for a TPDO that must not come."""
        return self.dut.pdo_silence_s


class Tpdo(TpdoParameters):
    """TPDO ``number`` (1: 1800h/1A00h)."""

    def __init__(self, dut: DeviceLink, number: int) -> None:
        if not 1 <= number <= TPDO_COUNT:
            raise IndexError(f"TPDO {number}: CiA 301 numbers TPDOs 1..{TPDO_COUNT}")
        self.dut = dut
        self.number = number
        self.comm = TPDO_COMMUNICATION.start + number - 1
