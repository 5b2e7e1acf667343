"""SDO server protocol engine (CiA 301 §7.2.4): expedited and segmented up/download, aborts.

The engine only speaks the protocol. Whether an object exists, may be read or written, and
what a write does is decided by the ``ObjectAccess`` it is given (the simulated node).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Protocol

from ..cia301 import SdoAbortCode

TOGGLE_NOT_ALTERNATED = SdoAbortCode.TOGGLE_BIT
COMMAND_INVALID = SdoAbortCode.COMMAND_SPECIFIER
GENERAL_ERROR = SdoAbortCode.GENERAL_ERROR


class SdoAbort(Exception):
    """Raised by an ObjectAccess to make the server answer with an abort frame."""

    def __init__(self, code: int) -> None:
        super().__init__(f"SDO abort 0x{code:08X}")
        self.code = code


class SdoNoReply(Exception):
    """Raised by an ObjectAccess when the device sends no response at all (e.g. it reboots)."""


class ObjectAccess(Protocol):
    def sdo_read(self, index: int, sub: int) -> bytes: ...

    def sdo_write(self, index: int, sub: int, data: bytes) -> None: ...


@dataclass
class _Transfer:
    upload: bool
    index: int
    sub: int
    toggle: int = 0
    data: bytearray = field(default_factory=bytearray)
    size: int | None = None


def abort_frame(index: int, sub: int, code: int) -> bytes:
    return struct.pack("<BHBI", 0x80, index, sub, code)


class SdoServer:
    """One SDO server channel. ``handle(request) -> response or None``."""

    def __init__(self, access: ObjectAccess) -> None:
        self._access = access
        self._transfer: _Transfer | None = None
        self._last_multiplexer: tuple[int, int] | None = None  # for aborts during segments

    def reset(self) -> None:
        """Drop a transfer in progress (NMT reset, power cycle)."""
        self._transfer = None

    def handle(self, request: bytes) -> bytes | None:
        """Answer one request frame; None means no response is sent."""
        if len(request) != 8:
            return None  # CiA 301: SDO frames have 8 data bytes; shorter frames are not answered
        ccs = request[0] >> 5
        index, sub = struct.unpack_from("<HB", request, 1)
        self._last_multiplexer = (self._transfer.index, self._transfer.sub) if self._transfer else None
        try:
            if ccs == 1:
                return self._initiate_download(request, index, sub)
            if ccs == 0:
                return self._download_segment(request)
            if ccs == 2:
                return self._initiate_upload(index, sub)
            if ccs == 3:
                return self._upload_segment(request)
            if ccs == 4:  # abort from the client: forget the transfer, no response
                self._transfer = None
                return None
            raise SdoAbort(COMMAND_INVALID)  # block transfer (5, 6) and reserved (7)
        except SdoNoReply:
            self._transfer = None
            return None
        except SdoAbort as abort:
            if ccs in (0, 3) and self._last_multiplexer is not None:
                index, sub = self._last_multiplexer
            self._transfer = None
            return abort_frame(index, sub, abort.code)

    # -- download (client writes) --------------------------------------------------------
    def _initiate_download(self, request: bytes, index: int, sub: int) -> bytes:
        self._transfer = None
        expedited, size_indicated = bool(request[0] & 0x02), bool(request[0] & 0x01)
        if expedited:
            length = 4 - ((request[0] >> 2) & 0x03) if size_indicated else 4
            self._access.sdo_write(index, sub, bytes(request[4 : 4 + length]))
        else:
            size = struct.unpack_from("<I", request, 4)[0] if size_indicated else None
            self._transfer = _Transfer(upload=False, index=index, sub=sub, size=size)
        return struct.pack("<BHB4x", 0x60, index, sub)

    def _download_segment(self, request: bytes) -> bytes:
        transfer = self._transfer
        if transfer is None or transfer.upload:
            raise SdoAbort(COMMAND_INVALID)
        toggle = (request[0] >> 4) & 1
        if toggle != transfer.toggle:
            raise SdoAbort(TOGGLE_NOT_ALTERNATED)
        unused = (request[0] >> 1) & 0x07
        transfer.data += request[1 : 8 - unused]
        response = bytes([0x20 | (toggle << 4)]) + bytes(7)
        transfer.toggle ^= 1
        if request[0] & 0x01:  # last segment
            self._transfer = None
            if transfer.size is not None and transfer.size != len(transfer.data):
                raise SdoAbort(SdoAbortCode.LENGTH_MISMATCH)
            self._access.sdo_write(transfer.index, transfer.sub, bytes(transfer.data))
        return response

    # -- upload (client reads) -----------------------------------------------------------
    def _initiate_upload(self, index: int, sub: int) -> bytes:
        self._transfer = None
        data = self._access.sdo_read(index, sub)
        if 1 <= len(data) <= 4:
            command = 0x43 | ((4 - len(data)) << 2)
            return struct.pack("<BHB", command, index, sub) + data.ljust(4, b"\x00")
        self._transfer = _Transfer(upload=True, index=index, sub=sub, data=bytearray(data))
        return struct.pack("<BHBI", 0x41, index, sub, len(data))

    def _upload_segment(self, request: bytes) -> bytes:
        transfer = self._transfer
        if transfer is None or not transfer.upload:
            raise SdoAbort(COMMAND_INVALID)
        toggle = (request[0] >> 4) & 1
        if toggle != transfer.toggle:
            raise SdoAbort(TOGGLE_NOT_ALTERNATED)
        chunk = bytes(transfer.data[:7])
        del transfer.data[:7]
        last = not transfer.data
        command = (toggle << 4) | ((7 - len(chunk)) << 1) | int(last)
        transfer.toggle ^= 1
        if last:
            self._transfer = None
        return bytes([command]) + chunk.ljust(7, b"\x00")
