"""What the twin's SDO server does with a request frame under 8 bytes, beyond ignoring it (the default twin).

CiA 301 draws every SDO frame with 8 data bytes and gives no rule for a shorter one (open readings sdo-short-frame
and sdo-short-frame-served, ``encoder_conformance/open_points/sdo.py``): these conformant variants refuse it, or serve
it where its bytes carry the request. Two faults beside them: a segmented download's last segment confirmed before
the write is checked, so a refused one draws two answers, at once or with the confirmation after the tester's window.
"""

from __future__ import annotations

import struct

from encoder_conformance.cia.cia301 import SdoClientCommand
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.sdo_channel import LATE_ANSWER_S
from encoder_conformance.sim.engine.sdo_server import COMMAND_INVALID, INITIATE_COMMANDS, SdoServer, abort_frame

FRAME_BYTES = 8


def _needed(frame: bytes) -> int:
    """The bytes a request needs to be served (the twin's own copy: the simulator shares no code with the tester).
    An upload initiate, or a download initiate without size: its multiplexer (4); an expedited download with size:
    its data; a segmented download initiate with size, an abort, an expedited download without size: all 8; a
    download segment: its data; an upload segment, a reserved or block command: its command byte."""
    command, ccs = frame[0], frame[0] >> 5
    if ccs == SdoClientCommand.INITIATE_UPLOAD:
        return 4
    if ccs == SdoClientCommand.INITIATE_DOWNLOAD:
        if command & 0x02:
            return FRAME_BYTES - (command >> 2 & 0x03) if command & 0x01 else FRAME_BYTES
        return FRAME_BYTES if command & 0x01 else 4
    if ccs == SdoClientCommand.DOWNLOAD_SEGMENT:
        return FRAME_BYTES - (command >> 1 & 0x07)
    return FRAME_BYTES if ccs == SdoClientCommand.ABORT else 1


@breaks(SdoServer, "short_frame_aborted")
class ShortFrameAborted(SdoServer):
    """A frame under 8 bytes is refused as an invalid command: abort 05040001h naming the multiplexer of the last
    initiate served (0000h.00 before the first), and a transfer left open ends (the stack seen doing it named the
    last request's, so its abort can look like the answer to the next read of the same entry)."""

    _previous: tuple[int, int] = (0, 0)

    def reset(self) -> None:
        super().reset()
        self._previous = (0, 0)

    def respond(self, request: bytes) -> list[bytes]:
        if len(request) >= FRAME_BYTES:
            if request[0] >> 5 in INITIATE_COMMANDS:
                self._previous = struct.unpack_from("<HB", request, 1)
            return super().respond(request)
        self.reset_transfer()
        return [abort_frame(*self._previous, COMMAND_INVALID)]

    def reset_transfer(self) -> None:
        self._transfer = None
        if self._block is not None:
            self._block.reset()


@breaks(SdoServer, "short_frame_served")
class ShortFrameServed(SdoServer):
    """A frame under 8 bytes whose bytes carry its request is served as that request with the missing bytes 0 (a
    5-byte upload with index and sub-index, a 6-byte expedited download of 2 bytes); a shorter one is ignored."""

    def respond(self, request: bytes) -> list[bytes]:
        if request and len(request) < FRAME_BYTES and len(request) >= _needed(request):
            return super().respond(request.ljust(FRAME_BYTES, b"\x00"))
        return super().respond(request)


@breaks(SdoServer, "last_segment_confirmed_then_aborted")
class LastSegmentConfirmedThenAborted(SdoServer):
    """The last segment of a segmented download is confirmed before the write is checked: a refused write (too long,
    read-only, out of range) draws the confirmation and then the abort, two answers to one request."""

    def respond(self, request: bytes) -> list[bytes]:
        transfer = self._transfer
        last_segment = (len(request) == FRAME_BYTES and request[0] >> 5 == SdoClientCommand.DOWNLOAD_SEGMENT
                        and request[0] & 0x01 and transfer is not None and not transfer.upload
                        and self.toggle_ok(transfer, request[0] >> 4 & 1))
        frames = super().respond(request)
        if last_segment and frames and frames[0][0] >> 5 == 4:  # the write was refused
            return [bytes([0x20 | (request[0] & 0x10)]) + bytes(7), *frames]
        return frames


@breaks(SdoServer, "confirmed_late_after_abort")
class ConfirmedLateAfterAbort(LastSegmentConfirmedThenAborted):
    """A refused segmented download's last segment draws its abort, and ``LATE_ANSWER_S`` later a confirmation too
    (after the tester's silence window on every shipped profile: only the late-frame ledger sees it)."""

    def respond(self, request: bytes) -> list[bytes]:
        frames = super().respond(request)
        if len(frames) == 2 and self._later is not None:
            confirmation = frames[0]
            self._later(LATE_ANSWER_S, lambda: [confirmation])
            return frames[1:]
        return frames
