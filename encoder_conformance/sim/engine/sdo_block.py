"""SDO block upload and download (CiA 301 §7.2.4.3.9-§7.2.4.3.16) for a twin whose profile declares it.

Used only where ``capabilities.block_sdo`` is true; otherwise the SDO server refuses block
initiates with 05040001h. The engine owns the SDO channel while a block transfer runs: during a
block download every frame is a segment (its first byte is a sequence number, not a command).
CRC: ``cia301.block_crc`` (CRC-16-CCITT, canopen's own implementation).
"""

from __future__ import annotations

import binascii
import struct
from dataclasses import dataclass, field
from enum import Enum, auto

from encoder_conformance.cia.cia301 import SDO_ABORT, SdoAbortCode, block_crc
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.sdo_server import Later, ObjectAccess, SdoAbort, abort_frame

#: the block size this server asks the client for in a block download (CiA 301: 1..127 segments)
DOWNLOAD_BLKSIZE = 127
SEGMENT_BYTES = 7


class _Phase(Enum):
    UPLOAD_INITIATED = auto()  # waiting for "start upload"
    UPLOAD_BLOCK_SENT = auto()  # waiting for the block acknowledgement
    UPLOAD_END_SENT = auto()  # waiting for the end response
    DOWNLOAD_SEGMENTS = auto()  # receiving segments
    DOWNLOAD_END = auto()  # waiting for "end block download"


@dataclass
class _Block:
    phase: _Phase
    index: int
    sub: int
    crc: bool
    data: bytearray = field(default_factory=bytearray)
    size: int | None = None
    blksize: int = DOWNLOAD_BLKSIZE
    done: int = 0  # upload: bytes acknowledged; download: in-order segments of the current block
    sent: int = 0  # upload: segments sent in the current block
    last_seen: bool = False  # download: the segment with c=1 arrived
    resync: bool = False  # download: a segment came out of order; the rest of that block is ignored


class BlockEngine:
    """One server's block transfers: ``handle(request) -> frames to send``."""

    def __init__(self, access: ObjectAccess, later: Later | None = None, timeout_s: float = 1.0) -> None:
        self._access = access
        self._block: _Block | None = None
        self._later = later  # the node runs a time-out's frames (variants only)
        self.timeout_s = timeout_s  #: the profile's timing.sdo_transfer_timeout_ms

    @property
    def in_progress(self) -> bool:
        return self._block is not None

    def reset(self) -> None:
        self._block = None

    def handle(self, request: bytes) -> list[bytes]:
        block = self._block
        index, sub = (block.index, block.sub) if block else struct.unpack_from("<HB", request, 1)
        try:
            if request[0] == SDO_ABORT:  # abort from the client (a segment cannot carry sequence number 0)
                self._block = None
                return []
            if block is None:
                return self._initiate(request, index, sub)
            return self._continue(block, request)
        except SdoAbort as abort:
            self._block = None
            return [abort_frame(index, sub, abort.code)]

    # -- decisions the faults change ---------------------------------------------------------
    def crc(self, data: bytes) -> int:
        return block_crc(data)

    def blksize_ok(self, blksize: int) -> bool:
        return 1 <= blksize <= 127

    def seqno_ok(self, block: _Block, seqno: int) -> bool:
        return seqno == block.done + 1

    def unused_in_last(self, size: int) -> int:
        """n of the end block upload frame: the bytes of the last segment that carry no data."""
        return (SEGMENT_BYTES - size % SEGMENT_BYTES) % SEGMENT_BYTES

    def data_of_last(self, unused: int) -> int:
        """How many bytes of the last download segment carry no data (the client's n)."""
        return unused

    def crc_ok(self, block: _Block, received: int) -> bool:
        return not block.crc or received == self.crc(bytes(block.data))

    # -- protocol ----------------------------------------------------------------------------
    def _initiate(self, request: bytes, index: int, sub: int) -> list[bytes]:
        ccs, subcommand, crc = request[0] >> 5, request[0] & 0x03, bool(request[0] & 0x04)
        if ccs == 5 and subcommand == 0:  # initiate block upload: blksize, pst
            blksize = request[4]
            if not self.blksize_ok(blksize):
                raise SdoAbort(SdoAbortCode.BLOCK_SIZE)
            data = self._access.sdo_read(index, sub)
            self._block = _Block(_Phase.UPLOAD_INITIATED, index, sub, crc, bytearray(data), blksize=blksize)
            return [struct.pack("<BHBI", 0xC6, index, sub, len(data))]  # scs 6, sc=1, s=1
        if ccs == 6 and request[0] & 0x01 == 0:  # initiate block download
            size = struct.unpack_from("<I", request, 4)[0] if request[0] & 0x02 else None
            self._block = _Block(_Phase.DOWNLOAD_SEGMENTS, index, sub, crc, size=size)
            return [struct.pack("<BHBB3x", 0xA4, index, sub, DOWNLOAD_BLKSIZE)]  # scs 5, sc=1
        raise SdoAbort(SdoAbortCode.COMMAND_SPECIFIER)

    def _continue(self, block: _Block, request: bytes) -> list[bytes]:
        if block.phase is _Phase.DOWNLOAD_SEGMENTS:
            return self._segment(block, request)
        command = request[0]
        if block.phase is _Phase.UPLOAD_INITIATED and command == 0xA3:  # start upload
            return self._send_block(block)
        if block.phase is _Phase.UPLOAD_BLOCK_SENT and command == 0xA2:  # block acknowledgement
            return self._acknowledged(block, request[1], request[2])
        if block.phase is _Phase.UPLOAD_END_SENT and command == 0xA1:  # end response
            self._block = None
            return []
        if block.phase is _Phase.DOWNLOAD_END and command & 0xE3 == 0xC1:  # end block download
            return self._end_download(block, (command >> 2) & 0x07, struct.unpack_from("<H", request, 1)[0])
        raise SdoAbort(SdoAbortCode.COMMAND_SPECIFIER)

    # -- upload ------------------------------------------------------------------------------
    def _send_block(self, block: _Block) -> list[bytes]:
        remaining = bytes(block.data[block.done:])
        frames = []
        for seqno in range(1, block.blksize + 1):
            chunk = remaining[(seqno - 1) * SEGMENT_BYTES : seqno * SEGMENT_BYTES]
            last = block.done + seqno * SEGMENT_BYTES >= len(block.data)
            frames.append(bytes([seqno | (0x80 if last else 0)]) + chunk.ljust(SEGMENT_BYTES, b"\x00"))
            if last:
                break
        block.sent = len(frames)
        block.phase = _Phase.UPLOAD_BLOCK_SENT
        return frames

    def _acknowledged(self, block: _Block, ackseq: int, blksize: int) -> list[bytes]:
        if ackseq > block.sent:
            raise SdoAbort(SdoAbortCode.SEQUENCE_NUMBER)
        if not self.blksize_ok(blksize):
            raise SdoAbort(SdoAbortCode.BLOCK_SIZE)
        block.done = min(len(block.data), block.done + ackseq * SEGMENT_BYTES)
        block.blksize = blksize
        if block.done < len(block.data):
            return self._send_block(block)
        unused = self.unused_in_last(len(block.data))
        block.phase = _Phase.UPLOAD_END_SENT
        crc = self.crc(bytes(block.data)) if block.crc else 0
        return [struct.pack("<BH5x", 0xC1 | unused << 2, crc)]

    # -- download ----------------------------------------------------------------------------
    def _segment(self, block: _Block, request: bytes) -> list[bytes]:
        seqno, last = request[0] & 0x7F, bool(request[0] & 0x80)
        if block.resync and seqno != 1:
            return []  # the rest of the block that went wrong: the client repeats it after our acknowledgement
        block.resync = False
        if not self.seqno_ok(block, seqno):
            block.resync = True
            # CiA 301 §7.2.4.3.13: ackseq names the last segment received in order; the client repeats the rest
            return [self._block_ack(block)]
        block.done += 1
        block.data += request[1:8]
        block.last_seen = last
        if last or block.done == block.blksize:
            return [self._block_ack(block)]
        return []

    def _block_ack(self, block: _Block) -> bytes:
        ack = struct.pack("<BBB5x", 0xA2, block.done, DOWNLOAD_BLKSIZE)
        block.done = 0
        block.blksize = DOWNLOAD_BLKSIZE
        if block.last_seen:
            block.phase = _Phase.DOWNLOAD_END
        return ack

    def _end_download(self, block: _Block, unused: int, crc: int) -> list[bytes]:
        unused = self.data_of_last(unused)
        if unused:
            del block.data[-unused:]
        if block.size is not None and block.size != len(block.data):
            raise SdoAbort(SdoAbortCode.LENGTH_MISMATCH)
        if not self.crc_ok(block, crc):
            raise SdoAbort(SdoAbortCode.CRC_ERROR)
        self._access.sdo_write(block.index, block.sub, bytes(block.data))
        self._block = None
        return [bytes([0xA1]) + bytes(7)]


# -- faults (fault_catalogue group test_sdo_protocol) -------------------------------------------
@breaks(BlockEngine, "block_crc_wrong")
class BlockCrcWrong(BlockEngine):
    """The CRC starts from FFFFh (CRC-16/CCITT-FALSE, a common mix-up): the upload's end frame carries a
    wrong one, and a download with the right CRC is refused."""

    def crc(self, data: bytes) -> int:
        return binascii.crc_hqx(data, 0xFFFF)


@breaks(BlockEngine, "block_crc_unchecked")
class BlockCrcUnchecked(BlockEngine):
    """A block download with a wrong CRC is written."""

    def unused_in_last(self, size: int) -> int:
        """n of the end block upload frame: the bytes of the last segment that carry no data."""
        return (SEGMENT_BYTES - size % SEGMENT_BYTES) % SEGMENT_BYTES

    def data_of_last(self, unused: int) -> int:
        """How many bytes of the last download segment carry no data (the client's n)."""
        return unused

    def crc_ok(self, block: _Block, received: int) -> bool:
        return True


@breaks(BlockEngine, "block_seqno_unchecked")
class BlockSeqnoUnchecked(BlockEngine):
    """Download segments are taken in whatever order their sequence numbers say."""

    def seqno_ok(self, block: _Block, seqno: int) -> bool:
        return True


@breaks(BlockEngine, "block_size_unchecked")
class BlockSizeUnchecked(BlockEngine):
    """A block size of 0 or over 127 is taken (as 127)."""

    def blksize_ok(self, blksize: int) -> bool:
        return True

    def _send_block(self, block: _Block) -> list[bytes]:
        block.blksize = block.blksize if 1 <= block.blksize <= 127 else 127
        return super()._send_block(block)


@breaks(BlockEngine, "block_upload_truncated")
class BlockUploadTruncated(BlockEngine):
    """The end block upload frame's n says one more unused byte than there is: the data comes one byte short."""

    def unused_in_last(self, size: int) -> int:
        return min(super().unused_in_last(size) + 1, SEGMENT_BYTES)


@breaks(BlockEngine, "block_end_size_ignored")
class BlockEndSizeIgnored(BlockEngine):
    """The n of end block download is ignored: the last segment's padding is taken as data (and refused)."""

    def data_of_last(self, unused: int) -> int:
        return 0


# -- conformant variants (encoder_conformance/open_points/sdo.py) ----------------------------------------------------
@breaks(BlockEngine, "slow_subblock_timeout")
class SlowSubblockTimeout(BlockEngine):
    """A download segment out of sequence is ignored; a sub-block left incomplete is acknowledged (ackseq: the
    segments received in order) after the profile's sdo_transfer_timeout_ms without a further segment
    (CANopenNode's reading; its sub-block time-out is 0.7 x its SDO time-out)."""

    _segments = 0  # segments received so far: a time-out armed before the last one is stale

    def _segment(self, block: _Block, request: bytes) -> list[bytes]:
        self._segments += 1
        if not self.seqno_ok(block, request[0] & 0x7F):
            frames: list[bytes] = []  # ignored: the acknowledgement waits for the time-out
        else:
            frames = super()._segment(block, request)
        if not frames and self._later is not None:
            armed = self._segments
            self._later(self.timeout_s, lambda: self._sub_block_timed_out(block, armed))
        return frames

    def _sub_block_timed_out(self, block: _Block, armed: int) -> list[bytes]:
        if self._block is not block or self._segments != armed or block.phase is not _Phase.DOWNLOAD_SEGMENTS:
            return []
        return [self._block_ack(block)]
