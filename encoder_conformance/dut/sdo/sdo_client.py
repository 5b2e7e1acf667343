"""A byte-exact SDO client that goes step by step (CiA 301 §7.2.4.3), for the protocol checks.

canopen's client hides what a protocol check must see: it retries, aborts with index 0, falls back
silently and stops at the first surprise. This one sends exactly the frame a step names (so a test
can put a wrong toggle bit, segment size, sequence number or CRC in it), returns the raw answer,
and its whole transfers (upload, download, block upload, block download) list every deviation
from CiA 301 they saw: a multiplexer not echoed, a toggle bit not alternated, a size that does not
add up, a CRC that does not match. Block CRC: ``cia301.block_crc`` (canopen's own CRC-16-CCITT).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

import can

from encoder_conformance.cia.cia301 import SDO_ABORT, SDO_REQUEST_BASE, SDO_RESPONSE_BASE, SdoAbortCode, block_crc
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.sdo.sdo_frames import SdoResponse, abort_name, expedited_download_request, upload_request
from encoder_conformance.dut.sdo.sdo_words import Stamped

SEGMENT_BYTES = 7
MAX_BLKSIZE = 127
#: what a further answer to an answered request breaks
ONE_ANSWER = "CiA 301 §7.2.4.3.4-7 (each SDO request confirmed once)"
#: what an answer to the client's abort breaks
UNCONFIRMED_ABORT = "CiA 301 §7.2.4.3.17 (abort SDO transfer: unconfirmed)"
#: a segmented transfer of unknown size is given up after this many segments (a device that never sets c)
MAX_SEGMENTS = 4096


@dataclass
class Transfer:
    """What a whole transfer brought: the data, the abort that ended it (if any), and what broke CiA 301."""

    data: bytes = b""
    abort: SdoResponse | None = None
    problems: list[str] = field(default_factory=list)
    responses: list[bytes] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.abort is None and not self.problems

    def describe(self) -> str:
        lines = [f"abort {abort_name(self.abort.abort_code or 0)}" if self.abort else "no abort", *self.problems]
        lines += ["responses: " + " | ".join(r.hex(" ").upper() for r in self.responses[-8:])]
        return "\n".join(lines)


def echoes(request: bytes, response: bytes) -> bool:
    """The response repeats the request's index and sub-index (bytes 1-3)."""
    return response[1:4] == request[1:4]


class SdoProtocolClient:
    """Frames of the SDO protocol, one step at a time, to the device's default SDO server."""

    def __init__(self, dut: DeviceLink) -> None:
        self.dut = dut

    # -- single steps ------------------------------------------------------------------------
    def request(self, frame: bytes, timeout: float | None = None) -> SdoResponse | None:
        return self.dut.sdo_request(frame, timeout=timeout)

    def expedited_download(self, index: int, sub: int, data: bytes, size_indicated: bool = True) -> SdoResponse | None:
        """Initiate download, e=1; with s=1 the n bits give the length, with s=0 all four bytes go."""
        if size_indicated:
            return self.request(expedited_download_request(index, sub, data))
        return self.request(struct.pack("<BHB", 0x22, index, sub) + data.ljust(4, b"\x00")[:4])

    def initiate_upload(self, index: int, sub: int) -> SdoResponse | None:
        return self.request(upload_request(index, sub))

    def initiate_download(self, index: int, sub: int, size: int | None) -> SdoResponse | None:
        """Initiate segmented download (e=0), with the size indicated unless ``size`` is None."""
        if size is None:
            return self.request(struct.pack("<BHB4x", 0x20, index, sub))
        return self.request(struct.pack("<BHBI", 0x21, index, sub, size))

    def download_segment(self, data: bytes, toggle: int, last: bool, unused: int | None = None,
                         timeout: float | None = None) -> SdoResponse | None:
        """Download segment: t, n (default: 7 less the data's length; pass another to lie), c."""
        n = SEGMENT_BYTES - len(data) if unused is None else unused
        command = (toggle & 1) << 4 | (n & 0x07) << 1 | int(last)
        return self.request(bytes([command]) + data.ljust(SEGMENT_BYTES, b"\x00")[:SEGMENT_BYTES], timeout)

    def upload_segment(self, toggle: int, timeout: float | None = None) -> SdoResponse | None:
        return self.request(bytes([0x60 | (toggle & 1) << 4]) + bytes(7), timeout)

    def abort(self, index: int, sub: int, code: int = SdoAbortCode.GENERAL_ERROR) -> Mark:
        """Abort SDO transfer from the client (unconfirmed: no answer is due); a mark before it."""
        return self.dut.send_sdo(struct.pack("<BHBI", SDO_ABORT, index, sub, code))

    def abort_unanswered(self, index: int, sub: int, code: int = SdoAbortCode.GENERAL_ERROR) -> list[bytes]:
        """Abort a transfer the device has no more frames of in flight (a segmented one: the server sends only on
        request) and watch the silence window; the SDO responses in it. An answer after it is still charged to the
        abort (the late-frame ledger). Not for a block upload: its sub-block may still be on its way."""
        request = struct.pack("<BHBI", SDO_ABORT, index, sub, code)
        answers = self.silent_after(self.dut.send_sdo(request))
        self.dut.frames.late.close_sdo(self.dut.node_id, request, "the client's abort", UNCONFIRMED_ABORT)
        return answers

    def silent_after(self, mark: Mark) -> list[bytes]:
        """The SDO responses within the SDO silence window after ``mark`` (none are due)."""
        return [bytes(m.data) for m in self.dut.frames.quiet_period(self.is_response, self.dut.sdo_silence_s, mark)]

    def exchange_since(self, mark: Mark) -> tuple[bytes, list[Stamped]]:
        """The first request sent after ``mark`` and every response to come within what the device owes plus the
        tester's margin (``sdo_silence_s``, watched from now): a second answer to one request shows here."""
        answers = self.dut.frames.quiet_period(self.is_response, self.dut.sdo_silence_s, mark)
        sent = self.dut.frames.since(mark, lambda m: not m.is_rx and m.arbitration_id == SDO_REQUEST_BASE
                                     + self.dut.node_id)
        request = bytes(sent[0].data) if sent else b""
        if request:  # a further answer after the window is still charged to the request (the late-frame ledger)
            self.dut.frames.late.close_sdo(self.dut.node_id, request, "an SDO request already answered",
                                           ONE_ANSWER)
        return request, [Stamped(bytes(m.data), m.timestamp) for m in answers]

    def is_response(self, msg: can.Message) -> bool:
        return msg.is_rx and msg.arbitration_id == SDO_RESPONSE_BASE + self.dut.node_id and not msg.is_remote_frame

    # -- whole transfers ---------------------------------------------------------------------
    def upload(self, index: int, sub: int) -> Transfer:
        """Upload as CiA 301 §7.2.4.3.4-7 goes, checking the initiate response and every segment."""
        result = Transfer()
        request = upload_request(index, sub)
        response = self._initiate(result, request, expected_scs=2)
        if response is None:
            return result
        command = response.raw[0]
        if command & 0x02:  # expedited: the data is in the initiate response
            length = 4 - ((command >> 2) & 0x03) if command & 0x01 else 4
            result.data = response.raw[4 : 4 + length]
            return result
        size = response.segmented_size
        return self._upload_segments(result, size)

    def _upload_segments(self, result: Transfer, size: int | None) -> Transfer:
        data = bytearray()
        limit = MAX_SEGMENTS if size is None else size // SEGMENT_BYTES + 2
        for number in range(limit):
            toggle = number & 1
            response = self.upload_segment(toggle)
            if not self._answered(result, response, f"upload segment {number + 1} (toggle {toggle})"):
                break
            assert response is not None
            if response.scs != 0:
                result.problems.append(f"upload segment {number + 1}: server command {response.raw[0]:02X}h is not an "
                                       f"upload segment response (scs 0)")
                break
            if (response.raw[0] >> 4) & 1 != toggle:
                result.problems.append(f"upload segment {number + 1}: toggle bit {(response.raw[0] >> 4) & 1}, the "
                                       f"request's was {toggle} (CiA 301 §7.2.4.3.7: the same toggle bit)")
            unused = (response.raw[0] >> 1) & 0x07
            data += response.raw[1 : 8 - unused]
            if response.raw[0] & 0x01:
                break
        else:
            result.problems.append(f"no last segment (c=1) after {limit} segments")
        result.data = bytes(data)
        if size is not None and len(data) != size:
            result.problems.append(f"the initiate response announced {size} bytes, the segments carried {len(data)}")
        return result

    def download(self, index: int, sub: int, data: bytes) -> Transfer:
        """Segmented download with the size indicated (CiA 301 §7.2.4.3.2-5), checking every response."""
        result = Transfer()
        if self._initiate(result, struct.pack("<BHBI", 0x21, index, sub, len(data)), expected_scs=3) is None:
            return result
        chunks = [data[i : i + SEGMENT_BYTES] for i in range(0, len(data), SEGMENT_BYTES)] or [b""]
        for number, chunk in enumerate(chunks):
            toggle = number & 1
            response = self.download_segment(chunk, toggle, last=number == len(chunks) - 1)
            if not self._answered(result, response, f"download segment {number + 1} (toggle {toggle})"):
                return result
            assert response is not None
            if response.scs != 1 or (response.raw[0] >> 4) & 1 != toggle:
                result.problems.append(f"download segment {number + 1}: response {response.raw.hex(' ').upper()} is "
                                       f"not a download segment response (scs 1) with toggle bit {toggle}")
                return result
        return result

    def _answered(self, result: Transfer, response: SdoResponse | None, what: str) -> bool:
        """Record the response; False (and why) where the transfer cannot go on: none came, or an abort."""
        if response is None:
            result.problems.append(f"{what}: no response within {self.dut.sdo_timeout * 1000:.0f} ms")
            return False
        result.responses.append(response.raw)
        if response.is_abort:
            result.abort = response
            return False
        return True

    def _initiate(self, result: Transfer, request: bytes, expected_scs: int) -> SdoResponse | None:
        """Send an initiate request; its response where the transfer may go on (a wrong multiplexer is noted)."""
        response = self.request(request)
        if not self._answered(result, response, f"initiate {request.hex(' ').upper()}"):
            return None
        assert response is not None
        if response.scs != expected_scs:
            result.problems.append(f"initiate: server command {response.raw[0]:02X}h, expected scs {expected_scs}")
            return None
        if not echoes(request, response.raw):
            result.problems.append(f"initiate response for {response.index:04X}h.{response.sub:02X}: it does not "
                                   f"echo the request's multiplexer {request[2]:02X}{request[1]:02X}h.{request[3]:02X} "
                                   "(CiA 301 §7.2.4.3)")
        return response

    # -- block transfer (CiA 301 §7.2.4.3.9-16) ------------------------------------------------
    def block_upload_initiate(self, index: int, sub: int, blksize: int, crc: bool = True,
                              pst: int = 0) -> SdoResponse | None:
        return self.request(struct.pack("<BHBBB2x", 0xA0 | int(crc) << 2, index, sub, blksize, pst))

    def block_download_initiate(self, index: int, sub: int, size: int | None, crc: bool = True) -> SdoResponse | None:
        command = 0xC0 | int(crc) << 2 | int(size is not None) << 1
        return self.request(struct.pack("<BHBI", command, index, sub, size or 0))

    def send_block_segment(self, seqno: int, data: bytes, last: bool) -> Mark:
        """One block download segment (no answer is due for it); a mark before it."""
        return self.dut.send_sdo(bytes([seqno & 0x7F | (0x80 if last else 0)]) + data.ljust(SEGMENT_BYTES, b"\x00"))

    def wait_response(self, after: Mark, timeout: float | None = None) -> SdoResponse | None:
        """The next SDO response after ``after`` (a block acknowledgement, an end frame, an abort)."""
        msg = self.dut.frames.wait_for(self.is_response, self.dut.sdo_timeout if timeout is None else timeout, after)
        return None if msg is None else SdoResponse(bytes(msg.data))

    def block_upload(self, index: int, sub: int, blksize: int = MAX_BLKSIZE, crc: bool = True) -> Transfer:
        """Block upload: initiate, start, sub-blocks acknowledged, end with the CRC checked."""
        result = Transfer()
        request = struct.pack("<BHBBB2x", 0xA0 | int(crc) << 2, index, sub, blksize, 0)
        response = self.request(request)
        if not self._answered(result, response, f"initiate block upload {index:04X}h.{sub:02X}"):
            return result
        assert response is not None
        if response.raw[0] & 0xE1 != 0xC0:  # scs 6, ss 0 (bit 2 sc, bit 1 s)
            result.problems.append(f"initiate block upload: response {response.raw[0]:02X}h is not scs 6, ss 0")
            return result
        if not echoes(request, response.raw):
            result.problems.append("initiate block upload response does not echo the multiplexer (CiA 301 §7.2.4.3.14)")
        server_crc = bool(response.raw[0] & 0x04)
        size = struct.unpack_from("<I", response.raw, 4)[0] if response.raw[0] & 0x02 else None
        data = bytearray()
        mark = self.dut.send_sdo(b"\xa3" + bytes(7))  # start upload
        while True:
            segments = self._sub_block(result, mark, blksize)
            if segments is None:
                return result
            expected = list(range(1, len(segments) + 1))
            if [s[0] & 0x7F for s in segments] != expected:
                result.problems.append(f"sub-block sequence numbers {[s[0] & 0x7F for s in segments]}, expected "
                                       f"{expected}")
                return result
            for segment in segments:
                data += segment[1:8]
            mark = self.dut.send_sdo(struct.pack("<BBB5x", 0xA2, len(segments), blksize))
            if segments[-1][0] & 0x80:
                break
        end = self._block_frame(result, mark, 0xC1, "end block upload (scs 6, ss 1)")
        if end is None:
            return result
        unused = (end.raw[0] >> 2) & 0x07
        result.data = bytes(data[: len(data) - unused])
        self.dut.send_sdo(b"\xa1" + bytes(7))  # end response
        if size is not None and size != len(result.data):
            result.problems.append(f"the initiate response announced {size} bytes, the sub-blocks carried "
                                   f"{len(result.data)}")
        received = struct.unpack_from("<H", end.raw, 1)[0]
        if crc and server_crc and received != block_crc(result.data):
            result.problems.append(f"end block upload CRC {received:04X}h, the data's CRC is "
                                   f"{block_crc(result.data):04X}h (CiA 301 §7.2.4.3.16)")
        return result

    def _sub_block(self, result: Transfer, mark: Mark, blksize: int) -> list[bytes] | None:
        """The segments of one sub-block (up to ``blksize``, or the one with c=1); None after an abort or silence."""
        seen: list[bytes] = []

        def ends_block(msg: can.Message) -> bool:
            if not self.is_response(msg):
                return False
            seen.append(bytes(msg.data))
            return bool(msg.data[0] & 0x80) or len(seen) >= blksize

        if self.dut.frames.wait_for(ends_block, self.dut.sdo_timeout, mark) is None:
            result.problems.append(f"sub-block: {len(seen)} segment(s) and no last one within "
                                   f"{self.dut.sdo_timeout * 1000:.0f} ms")
            return None
        result.responses += seen
        if seen[-1][0] == SDO_ABORT and len(seen) == 1:  # an abort (sequence number 0 is no segment)
            result.abort = SdoResponse(seen[-1])
            return None
        return seen

    def block_download(self, index: int, sub: int, data: bytes, crc: bool = True,
                       crc_value: int | None = None) -> Transfer:
        """Block download: initiate, sub-blocks, end with the CRC (``crc_value`` to send a wrong one)."""
        result = Transfer()
        command = 0xC0 | int(crc) << 2 | 0x02
        request = struct.pack("<BHBI", command, index, sub, len(data))
        response = self.request(request)
        if not self._answered(result, response, f"initiate block download {index:04X}h.{sub:02X}"):
            return result
        assert response is not None
        if response.raw[0] & 0xE3 != 0xA0 or not 1 <= response.raw[4] <= MAX_BLKSIZE:
            result.problems.append(f"initiate block download: response {response.raw.hex(' ').upper()} is not scs 5, "
                                   "ss 0 with a block size 1..127")
            return result
        if not echoes(request, response.raw):
            result.problems.append("initiate block download response does not echo the multiplexer "
                                   "(CiA 301 §7.2.4.3.10)")
        server_crc, blksize = bool(response.raw[0] & 0x04), response.raw[4]
        chunks = [data[i : i + SEGMENT_BYTES] for i in range(0, len(data), SEGMENT_BYTES)] or [b""]
        done = 0
        while done < len(chunks):
            block = chunks[done : done + blksize]
            mark = self.dut.frames.mark()
            for seqno, chunk in enumerate(block, start=1):
                self.send_block_segment(seqno, chunk, last=done + seqno == len(chunks))
            ack = self.wait_response(mark)
            if not self._answered(result, ack, f"block acknowledgement after segment {done + len(block)}"):
                return result
            assert ack is not None
            if ack.raw[0] & 0xE3 != 0xA2 or ack.raw[1] > len(block) or not 1 <= ack.raw[2] <= MAX_BLKSIZE:
                result.problems.append(f"block acknowledgement {ack.raw.hex(' ').upper()}: not scs 5, ss 2 with "
                                       f"ackseq 0..{len(block)} and a block size 1..127")
                return result
            done, blksize = done + ack.raw[1], ack.raw[2]
        unused = (SEGMENT_BYTES - len(data) % SEGMENT_BYTES) % SEGMENT_BYTES
        value = block_crc(data) if crc_value is None else crc_value
        end = struct.pack("<BH5x", 0xC1 | unused << 2, value if crc and server_crc else 0)
        self._block_frame(result, self.dut.send_sdo(end), 0xA1, "end block download response (scs 5, ss 1)")
        return result

    def _block_frame(self, result: Transfer, mark: Mark, command: int, what: str) -> SdoResponse | None:
        """The next response after ``mark`` where it is the block frame ``command`` (scs and ss, mask E3h)."""
        response = self.wait_response(mark)
        if not self._answered(result, response, what):
            return None
        assert response is not None
        if response.raw[0] & 0xE3 != command:
            result.problems.append(f"{what}: got {response.raw.hex(' ').upper()}")
            return None
        return response
