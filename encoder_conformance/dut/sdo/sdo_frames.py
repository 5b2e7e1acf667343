"""Byte-exact SDO request builders and response parsers (CiA 301 §7.2.4.3).

Used where canopen's client cannot be trusted for conformance checks (it aborts with index 0,
retries, hides the raw response; reference/python-stack-measured.md §2.3).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import SDO_ABORT, SDO_ANSWER, SdoAbortCode, SdoClientCommand, SdoServerCommand


def upload_request(index: int, sub: int) -> bytes:
    return struct.pack("<BHB4x", 0x40, index, sub)


def expedited_download_request(index: int, sub: int, data: bytes) -> bytes:
    if not 1 <= len(data) <= 4:
        raise ValueError("an expedited download carries 1 to 4 bytes")
    command = 0x23 | ((4 - len(data)) << 2)
    return struct.pack("<BHB", command, index, sub) + data.ljust(4, b"\x00")


ABORT_SCS = SdoServerCommand.ABORT
ANSWER_SCS = SDO_ANSWER  # client command specifier -> the server command specifier of its answer
BLOCK_CCS = (SdoClientCommand.BLOCK_UPLOAD, SdoClientCommand.BLOCK_DOWNLOAD)
#: initiate requests: the answer (also an abort) repeats index and sub-index
ECHOES_MULTIPLEXER = {SdoClientCommand.INITIATE_DOWNLOAD, SdoClientCommand.INITIATE_UPLOAD, *BLOCK_CCS}
#: the bits of an initiate request's command byte that CiA 301 marks "x: not used, always 0" (§7.2.4.3.3 initiate
#: download: bit 4; §7.2.4.3.6 initiate upload: bits 4-0)
INITIATE_RESERVED_BITS: dict[int, int] = {SdoClientCommand.INITIATE_DOWNLOAD: 0x10,
                                          SdoClientCommand.INITIATE_UPLOAD: 0x1F}


def reserved_bits_set(request: bytes) -> bool:
    """An initiate request with a bit set that CiA 301 says is always 0: no valid initiate. The device may serve it
    as if the bits were 0, or refuse it as an invalid command (open reading sdo-initiate-reserved-bits)."""
    return bool(request) and bool(request[0] & INITIATE_RESERVED_BITS.get(request[0] >> 5, 0))


def refused_as_invalid(request: bytes, reply: bytes) -> bool:
    """``reply`` refuses ``request``, an initiate with reserved bits set, as an invalid command: abort 05040001h with
    any multiplexer (no text gives one for a frame that is no valid request; CANopenNode names its previous
    transfer's). A request with the bits 0 is a valid initiate: its abort echoes its multiplexer."""
    return (reserved_bits_set(request) and len(reply) == 8 and reply[0] >> 5 == ABORT_SCS
            and struct.unpack_from("<I", reply, 4)[0] == SdoAbortCode.COMMAND_SPECIFIER)


def answers(request: bytes, reply: bytes) -> bool:
    """True when ``reply`` can be the server's answer to ``request``: the matching server command (or an
    abort) and, for an initiate request, the same multiplexer (an abort of a block initiate, or the 05040001h
    that refuses an initiate with reserved bits set, with any). A reply that fits no open request is a
    stale one (a late answer to an earlier request), never the answer to this one.
    """
    if not request or not reply:
        return False
    ccs, scs = request[0] >> 5, reply[0] >> 5
    if ccs not in ANSWER_SCS:
        return True  # a reserved command specifier: whatever comes is the device's answer to it
    if scs not in (ANSWER_SCS[ccs], ABORT_SCS):
        return False
    if ccs in ECHOES_MULTIPLEXER and len(request) >= 4 and len(reply) >= 4:
        return (reply[1:4] == request[1:4] or (scs == ABORT_SCS and ccs in BLOCK_CCS)
                or refused_as_invalid(request, reply))
    return True


def abort_name(code: int) -> str:
    """'06010002h (Attempt to write a read only object)' using canopen's abort table."""
    text = SdoAbortedError.CODES.get(code, "not a CiA 301 abort code")
    return f"{code:08X}h ({text})"


@dataclass(frozen=True)
class SdoResponse:
    """A parsed server response frame."""

    raw: bytes

    @property
    def scs(self) -> int:
        return self.raw[0] >> 5

    @property
    def is_abort(self) -> bool:
        return self.raw[0] == SDO_ABORT

    @property
    def index(self) -> int:
        return struct.unpack_from("<H", self.raw, 1)[0]

    @property
    def sub(self) -> int:
        return self.raw[3]

    @property
    def abort_code(self) -> int | None:
        return struct.unpack_from("<I", self.raw, 4)[0] if self.is_abort else None

    @property
    def expedited_size(self) -> int | None:
        """Data length of an expedited upload response with size indicated, else None."""
        if self.scs == 2 and self.raw[0] & 0x03 == 0x03:
            return 4 - ((self.raw[0] >> 2) & 0x03)
        return None

    @property
    def segmented_size(self) -> int | None:
        """Size announced by a segmented upload initiate response (e=0, s=1)."""
        if self.scs == 2 and self.raw[0] & 0x03 == 0x01:
            return struct.unpack_from("<I", self.raw, 4)[0]
        return None

    def describe(self) -> str:
        if self.is_abort:
            return f"abort {abort_name(self.abort_code or 0)} for {self.index:04X}h.{self.sub:02X}"
        return f"response {self.raw.hex(' ').upper()}"
