"""SDO server protocol engine (CiA 301 §7.2.4): expedited and segmented up/download, aborts.

The engine only speaks the protocol. Whether an object exists, may be read or written, and
what a write does is decided by the ``ObjectAccess`` it is given (the simulated node).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from encoder_conformance.cia.cia301 import SDO_ABORT, SdoAbortCode, SdoClientCommand
from encoder_conformance.errors import SdoAbort, SdoNoReply
from encoder_conformance.sim.engine.faults import breaks

TOGGLE_NOT_ALTERNATED = SdoAbortCode.TOGGLE_BIT
COMMAND_INVALID = SdoAbortCode.COMMAND_SPECIFIER
GENERAL_ERROR = SdoAbortCode.GENERAL_ERROR
BLOCK_COMMANDS = (SdoClientCommand.BLOCK_UPLOAD, SdoClientCommand.BLOCK_DOWNLOAD)
INITIATE_COMMANDS = (SdoClientCommand.INITIATE_DOWNLOAD, SdoClientCommand.INITIATE_UPLOAD)
SEGMENT_COMMANDS = (SdoClientCommand.DOWNLOAD_SEGMENT, SdoClientCommand.UPLOAD_SEGMENT)


class ObjectAccess(Protocol):
    def sdo_read(self, index: int, sub: int) -> bytes: ...

    def sdo_write(self, index: int, sub: int, data: bytes) -> None: ...


#: ``later(delay_s, produce)``: after ``delay_s`` the node calls ``produce()`` and sends the frames it returns (the
#: server's own time-outs: a transfer left open, a sub-block left incomplete)
Later = Callable[[float, Callable[[], list[bytes]]], None]


class BlockTransfers(Protocol):
    """Block transfers (sim/engine/sdo_block.py), where the profile declares them."""

    @property
    def in_progress(self) -> bool: ...

    def reset(self) -> None: ...

    def handle(self, request: bytes) -> list[bytes]: ...


@dataclass
class _Transfer:
    upload: bool
    index: int
    sub: int
    toggle: int = 0
    data: bytearray = field(default_factory=bytearray)
    size: int | None = None


def abort_frame(index: int, sub: int, code: int) -> bytes:
    return struct.pack("<BHBI", SDO_ABORT, index, sub, code)


class SdoServer:
    """One SDO server channel. ``handle(request) -> response or None``."""

    def __init__(self, access: ObjectAccess, block: Callable[..., BlockTransfers] | None = None,
                 later: Later | None = None, timeout_s: float = 1.0) -> None:
        self._access = access
        self._transfer: _Transfer | None = None
        self._last_multiplexer: tuple[int, int] | None = None  # for aborts during segments
        self._later = later
        self.timeout_s = timeout_s  #: the profile's timing.sdo_transfer_timeout_ms (what the variants wait)
        # where the profile declares block transfer
        self._block = block(access, later=later, timeout_s=timeout_s) if block is not None else None

    def reset(self) -> None:
        """Drop a transfer in progress (NMT reset, power cycle)."""
        self._transfer = None
        if self._block is not None:
            self._block.reset()

    def respond(self, request: bytes) -> list[bytes]:
        """Every frame the server sends for one request: one response, none, or a block's segments."""
        if len(request) != 8:
            return []
        if self._block is not None and (self._block.in_progress or request[0] >> 5 in BLOCK_COMMANDS):
            if not self._block.in_progress:
                self._transfer = None  # a new request ends a segmented transfer left open
            return self._block.handle(request)
        if request[0] >> 5 in BLOCK_COMMANDS and not self.answers_block_initiate():
            return []
        response = self.handle(request)
        return [] if response is None else [response]

    def answers_block_initiate(self) -> bool:
        """Without block transfer, a block initiate is refused with an abort (handle() sends 05040001h)."""
        return True

    def handle(self, request: bytes) -> bytes | None:
        """Answer one request frame; None means no response is sent."""
        if len(request) != 8:
            return None  # CiA 301: SDO frames have 8 data bytes; shorter frames are not answered
        ccs = request[0] >> 5
        index, sub = struct.unpack_from("<HB", request, 1)
        self._last_multiplexer = (self._transfer.index, self._transfer.sub) if self._transfer else None
        if ccs in INITIATE_COMMANDS and self._transfer is not None and not self.serves_while_open():
            return None
        try:
            if ccs == SdoClientCommand.INITIATE_DOWNLOAD:
                return self._initiate_download(request, index, sub)
            if ccs == SdoClientCommand.DOWNLOAD_SEGMENT:
                return self._download_segment(request)
            if ccs == SdoClientCommand.INITIATE_UPLOAD:
                return self._initiate_upload(index, sub)
            if ccs == SdoClientCommand.UPLOAD_SEGMENT:
                return self._upload_segment(request)
            if ccs == SdoClientCommand.ABORT:  # abort from the client: forget the transfer, no response
                self.client_aborted()
                return None
            raise SdoAbort(COMMAND_INVALID)  # block transfer (5, 6) and reserved (7)
        except SdoNoReply:
            self._transfer = None
            return None
        except SdoAbort as abort:
            if ccs in SEGMENT_COMMANDS and self._last_multiplexer is not None:
                index, sub = self._last_multiplexer
            self._transfer = None
            return abort_frame(index, sub, abort.code)

    def client_aborted(self) -> None:
        """CiA 301 §7.2.4.3.17: an abort ends the transfer; it is not answered."""
        self._transfer = None

    def serves_while_open(self) -> bool:
        """A new initiate request while a segmented transfer is open ends that one and is served."""
        return True

    def toggle_ok(self, transfer: _Transfer, toggle: int) -> bool:
        return toggle == transfer.toggle

    def segment_data(self, request: bytes) -> bytes:
        """The data of a download segment: 7 bytes less the n unused ones its command byte states."""
        unused = (request[0] >> 1) & 0x07
        return request[1 : 8 - unused]

    def initiate_response(self, command: int, index: int, sub: int, payload: bytes) -> bytes:
        """An initiate response: it echoes the request's multiplexer (CiA 301 §7.2.4.3.3, §7.2.4.3.6)."""
        return struct.pack("<BHB", command, index, sub) + payload.ljust(4, b"\x00")

    def upload_data(self, index: int, sub: int) -> bytes:
        return self._access.sdo_read(index, sub)

    def upload_chunk(self, transfer: _Transfer) -> bytes:
        """The next up to 7 bytes of a segmented upload."""
        chunk = bytes(transfer.data[:7])
        del transfer.data[:7]
        return chunk

    def expedited_length(self, index: int, sub: int) -> int:
        """Bytes an expedited download without size indicator carries: the object's own size (CiA 301
        §7.2.4.3.3: e=1, s=0, "d contains unspecified number of bytes"), else all 4."""
        declared = getattr(self._access, "declared_size", None)
        size = declared(index, sub) if declared is not None else None
        return size if size is not None and 1 <= size <= 4 else 4

    # -- download (client writes) --------------------------------------------------------
    def _initiate_download(self, request: bytes, index: int, sub: int) -> bytes:
        self._transfer = None
        expedited, size_indicated = bool(request[0] & 0x02), bool(request[0] & 0x01)
        if expedited:
            length = 4 - ((request[0] >> 2) & 0x03) if size_indicated else self.expedited_length(index, sub)
            self._access.sdo_write(index, sub, bytes(request[4 : 4 + length]))
        else:
            size = struct.unpack_from("<I", request, 4)[0] if size_indicated else None
            self._transfer = _Transfer(upload=False, index=index, sub=sub, size=size)
        return self.initiate_response(0x60, index, sub, b"")

    def _download_segment(self, request: bytes) -> bytes:
        transfer = self._transfer
        if transfer is None or transfer.upload:
            raise SdoAbort(COMMAND_INVALID)
        toggle = (request[0] >> 4) & 1
        if not self.toggle_ok(transfer, toggle):
            raise SdoAbort(TOGGLE_NOT_ALTERNATED)
        transfer.data += self.segment_data(request)
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
        data = self.upload_data(index, sub)
        if 1 <= len(data) <= 4:
            return self.initiate_response(0x43 | ((4 - len(data)) << 2), index, sub, data)
        self._transfer = _Transfer(upload=True, index=index, sub=sub, data=bytearray(data))
        return self.initiate_response(0x41, index, sub, struct.pack("<I", len(data)))

    def _upload_segment(self, request: bytes) -> bytes:
        transfer = self._transfer
        if transfer is None or not transfer.upload:
            raise SdoAbort(COMMAND_INVALID)
        toggle = (request[0] >> 4) & 1
        if not self.toggle_ok(transfer, toggle):
            raise SdoAbort(TOGGLE_NOT_ALTERNATED)
        chunk = self.upload_chunk(transfer)
        last = not transfer.data
        command = (toggle << 4) | ((7 - len(chunk)) << 1) | int(last)
        transfer.toggle ^= 1
        if last:
            self._transfer = None
        return bytes([command]) + chunk.ljust(7, b"\x00")


# -- conformant variants (encoder_conformance/open_points/sdo.py) ----------------------------------------------------
def _interrupts(server: SdoServer, request: bytes) -> bool:
    """An initiate request (expedited or segmented up/download) while a segmented transfer is open."""
    return len(request) == 8 and request[0] >> 5 in (1, 2) and server._transfer is not None


@breaks(SdoServer, "interrupt_aborts_open_transfer")
class InterruptAbortsOpenTransfer(SdoServer):
    """A new initiate request during a segmented transfer: an abort (08000000h) naming the open transfer, then the
    new request's answer."""

    def respond(self, request: bytes) -> list[bytes]:
        transfer = self._transfer
        if transfer is None or not _interrupts(self, request):
            return super().respond(request)
        self._transfer = None
        return [abort_frame(transfer.index, transfer.sub, GENERAL_ERROR), *super().respond(request)]


@breaks(SdoServer, "interrupt_consumed_by_open_transfer")
class InterruptConsumedByOpenTransfer(SdoServer):
    """A new initiate request during a segmented transfer is taken as a wrong frame of that transfer: abort 05040001h
    naming it, and no answer to the request itself (CANopenNode)."""

    def respond(self, request: bytes) -> list[bytes]:
        transfer = self._transfer
        if transfer is None or not _interrupts(self, request):
            return super().respond(request)
        self._transfer = None
        return [abort_frame(transfer.index, transfer.sub, COMMAND_INVALID)]


#: the bits of an initiate request's command byte that CiA 301 marks "x: not used, always 0" (§7.2.4.3.3 download:
#: bit 4; §7.2.4.3.6 upload: bits 4-0). The twin's own copy: the simulator shares no code with the tester.
_INITIATE_RESERVED_BITS: dict[int, int] = {SdoClientCommand.INITIATE_DOWNLOAD: 0x10,
                                           SdoClientCommand.INITIATE_UPLOAD: 0x1F}


@breaks(SdoServer, "initiate_reserved_bits_refused")
class InitiateReservedBitsRefused(SdoServer):
    """An initiate request with a reserved bit set is no initiate: it is refused as an invalid command, abort 05040001h
    naming the multiplexer of the last valid initiate (0000h.00 before the first), and a transfer left open ends
    (CANopenNode: only 40h is an upload request, and its abort carries the index and sub-index it last took in)."""

    _previous: tuple[int, int] = (0, 0)

    def reset(self) -> None:
        super().reset()
        self._previous = (0, 0)

    def respond(self, request: bytes) -> list[bytes]:
        initiate = len(request) == 8 and request[0] >> 5 in _INITIATE_RESERVED_BITS
        if not initiate or (self._block is not None and self._block.in_progress):
            return super().respond(request)
        if request[0] & _INITIATE_RESERVED_BITS[request[0] >> 5]:
            self._transfer = None
            return [abort_frame(*self._previous, COMMAND_INVALID)]
        index, sub = struct.unpack_from("<HB", request, 1)
        self._previous = (index, sub)
        return super().respond(request)


@breaks(SdoServer, "left_open_transfer_times_out")
class LeftOpenTransferTimesOut(SdoServer):
    """A segmented transfer without a request for 25 ms (a short time-out, within any profile's
    sdo_transfer_timeout_ms: CiA 301 gives none) is aborted 05040000h naming its entry. Short, so that the abort
    comes while a test still watches the transfer it left open."""

    short_timeout_s = 0.025
    _requests = 0  # requests served so far: a time-out armed before the last one is stale

    def respond(self, request: bytes) -> list[bytes]:
        self._requests += 1
        frames = super().respond(request)
        transfer, armed = self._transfer, self._requests
        if transfer is not None and self._later is not None:
            self._later(min(self.short_timeout_s, self.timeout_s), lambda: self._timed_out(transfer, armed))
        return frames

    def _timed_out(self, transfer: _Transfer, armed: int) -> list[bytes]:
        if self._transfer is not transfer or self._requests != armed:
            return []
        self._transfer = None
        return [abort_frame(transfer.index, transfer.sub, SdoAbortCode.TIMEOUT)]


# -- faults: each breaks one decision above (fault_catalogue group test_sdo_protocol) ---------------
@breaks(SdoServer, "toggle_bit_ignored")
class ToggleBitIgnored(SdoServer):
    def toggle_ok(self, transfer: _Transfer, toggle: int) -> bool:
        return True


@breaks(SdoServer, "segmented_upload_truncated")
class SegmentedUploadTruncated(SdoServer):
    """The last segment of an upload lacks its last byte (the initiate response announced them all)."""

    def upload_data(self, index: int, sub: int) -> bytes:
        return self._access.sdo_read(index, sub)

    def upload_chunk(self, transfer: _Transfer) -> bytes:
        chunk = super().upload_chunk(transfer)
        return chunk if transfer.data else chunk[:-1]


@breaks(SdoServer, "long_reads_refused")
class LongReadsRefused(SdoServer):
    """Every read of an entry over 4 bytes is refused (08000000h): no segmented upload is left to judge."""

    def upload_data(self, index: int, sub: int) -> bytes:
        data = super().upload_data(index, sub)
        if len(data) > 4:
            raise SdoAbort(SdoAbortCode.GENERAL_ERROR)
        return data


@breaks(SdoServer, "segment_size_ignored")
class SegmentSizeIgnored(SdoServer):
    """A download segment's n bits are ignored: all 7 bytes are taken as data."""

    def segment_data(self, request: bytes) -> bytes:
        return request[1:8]


@breaks(SdoServer, "client_abort_ignored")
class ClientAbortIgnored(SdoServer):
    """An abort from the client leaves the transfer open: the next segment request continues it."""

    def client_aborted(self) -> None:
        return


@breaks(SdoServer, "open_transfer_blocks_requests")
class OpenTransferBlocksRequests(SdoServer):
    """While a segmented transfer is open, initiate requests go unanswered (the server waits for segments)."""

    def serves_while_open(self) -> bool:
        return False


@breaks(SdoServer, "download_response_wrong_mux")
class DownloadResponseWrongMux(SdoServer):
    """Download confirmations (60h) carry the next sub-index (canopen's client does not check it there)."""

    def initiate_response(self, command: int, index: int, sub: int, payload: bytes) -> bytes:
        return super().initiate_response(command, index, (sub + 1) & 0xFF if command == 0x60 else sub, payload)


@breaks(SdoServer, "expedited_upload_padded")
class ExpeditedUploadPadded(SdoServer):
    """Expedited uploads of 1- and 2-byte entries carry 4 bytes (n = 0): the size bits say 4."""

    def upload_data(self, index: int, sub: int) -> bytes:
        data = super().upload_data(index, sub)
        declared = getattr(self._access, "declared_size", lambda i, s: None)(index, sub)
        return data.ljust(4, b"\x00") if declared in (1, 2) else data


@breaks(SdoServer, "block_initiate_unanswered")
class BlockInitiateUnanswered(SdoServer):
    """A device without block transfer does not answer a block initiate at all (no abort)."""

    def answers_block_initiate(self) -> bool:
        return False


@breaks(SdoServer, "unsized_download_takes_four_bytes")
class UnsizedDownloadTakesFourBytes(SdoServer):
    """An expedited download without size indicator is taken as 4 bytes (so refused for smaller objects)."""

    def expedited_length(self, index: int, sub: int) -> int:
        return 4
