"""Faults of the SDO channel that only odd request sequences show (made for suites/test_sdo_fuzz.py).

Each is a small subclass of ``SdoChannel`` (see ``sim/engine/faults.py``): a device that dies on a short
frame, answers twice, answers what it must ignore, crashes on a second initiate, reports a
refused request as an error (EMCY), goes silent altogether after a reserved command specifier, or
echoes a wrong multiplexer in every reply (which the run's start-up check already shows).
"""

from __future__ import annotations

import struct

from encoder_conformance.cia.cia301 import EMCY_BASE, SDO_ABORT, SDO_RESPONSE_BASE, SdoAbortCode
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.heartbeat import HeartbeatProducer
from encoder_conformance.sim.engine.hooks import NodeHooks
from encoder_conformance.sim.engine.sdo_channel import SdoChannel

ABORT = SDO_ABORT
#: EMCY error code 8100h (communication, generic: CiA 301 §7.2.7.3.2 table 21), error register bit 4
EMCY_COMMUNICATION = struct.pack("<HB5x", 0x8100, 0x11)
RESERVED_CCS = 7  # client command specifier 7: reserved (CiA 301 §7.2.4.3.17 05040001h)


@breaks(SdoChannel, "dead_after_short_frame")
class DeadAfterShortFrame(SdoChannel):
    """After a frame shorter than 8 bytes the SDO server never answers again (until a reset)."""

    _dead = False

    def register(self, hooks: NodeHooks) -> None:
        super().register(hooks)
        hooks.halted.append(self._revive)

    def _revive(self) -> None:
        self._dead = False

    def serves(self, request: bytes) -> bool:
        self._dead = self._dead or len(request) < 8
        return not self._dead and super().serves(request)


@breaks(SdoChannel, "double_abort")
class DoubleAbort(SdoChannel):
    """Every abort frame goes out twice."""

    def answer(self, response: bytes) -> bytes | None:
        if response[0] == ABORT:
            self._send(SDO_RESPONSE_BASE + self._node_id(), response)
        return super().answer(response)


@breaks(SdoChannel, "answers_short_frame_with_garbage")
class AnswersShortFrames(SdoChannel):
    """A frame shorter than 8 bytes is answered with its own bytes padded to 8 (a driver echoing garbage)."""

    def on_request(self, request: bytes) -> None:
        if len(request) < 8 and self.serves(request):
            self._send(SDO_RESPONSE_BASE + self._node_id(), request.ljust(8, b"\x00"))
            return
        super().on_request(request)


@breaks(SdoChannel, "answers_client_abort")
class AnswersClientAbort(SdoChannel):
    """A client's abort transfer request is answered with the same abort frame (CiA 301: unconfirmed)."""

    def on_request(self, request: bytes) -> None:
        super().on_request(request)
        if len(request) == 8 and request[0] >> 5 == 4 and self.serves(request):
            self._send(SDO_RESPONSE_BASE + self._node_id(), request)


@breaks(SdoChannel, "crashes_on_interleaved_initiate")
class CrashesOnInterleavedInitiate(SdoChannel):
    """An initiate request while a segmented transfer is open stops the SDO server (until a reset)."""

    _open = False
    _dead = False

    def register(self, hooks: NodeHooks) -> None:
        super().register(hooks)
        hooks.halted.append(self._revive)

    def _revive(self) -> None:
        self._open = self._dead = False

    def on_request(self, request: bytes) -> None:
        ccs = request[0] >> 5 if len(request) == 8 else None
        if self._open and ccs in (1, 2):
            self._dead = True
        if self._dead:
            return
        self._request = request
        if ccs == 4:
            self._open = False
        super().on_request(request)

    def answer(self, response: bytes) -> bytes | None:
        request, ccs = self._request, self._request[0] >> 5
        if response[0] == ABORT:
            self._open = False
        elif ccs == 2 or (ccs == 1 and not request[0] & 0x02):
            self._open = not response[0] & 0x02 if ccs == 2 else True
        elif ccs in (0, 3):
            self._open = not (request if ccs == 0 else response)[0] & 0x01
        return super().answer(response)


@breaks(SdoChannel, "emcy_on_unknown_command")
class EmcyOnUnknownCommand(SdoChannel):
    """An abort for an unknown command specifier also sends an EMCY (communication error 8100h)."""

    def answer(self, response: bytes) -> bytes | None:
        if response[0] == ABORT and struct.unpack_from("<I", response, 4)[0] == SdoAbortCode.COMMAND_SPECIFIER:
            self._send(EMCY_BASE + self._node_id(), EMCY_COMMUNICATION)
        return super().answer(response)


@breaks(SdoChannel, "silent_after_reserved_command")
class SilentAfterReservedCommand(SdoChannel):
    """After a request with the reserved command specifier 7 the device hangs: no SDO answer and no heartbeat
    from then on (its NMT handler still runs: reset node or a power cycle brings it back)."""

    _silent = False

    def register(self, hooks: NodeHooks) -> None:
        super().register(hooks)
        self._hooks = hooks
        hooks.halted.append(self._revive)

    def _revive(self) -> None:
        self._silent = False  # the heartbeat restarts at the boot-up (HeartbeatProducer registers for it)

    def serves(self, request: bytes) -> bool:
        if self._silent or not super().serves(request):
            return False
        if len(request) == 8 and request[0] >> 5 == RESERVED_CCS:
            self._silent = True
            for restart in self._hooks.booted:  # the heartbeat producer: the one behaviour that sends by itself
                producer = getattr(restart, "__self__", None)
                if isinstance(producer, HeartbeatProducer):
                    producer.stop()
            return False
        return True


@breaks(SdoChannel, "sdo_reply_wrong_mux")
class ReplyWrongMultiplexer(SdoChannel):
    """Every reply that carries a multiplexer (initiate responses, aborts) names the next sub-index."""

    def answer(self, response: bytes) -> bytes | None:
        if response[0] >> 5 in (2, 3, 4):  # upload / download initiate response, abort
            response = response[:3] + bytes([(response[3] + 1) & 0xFF]) + response[4:]
        return super().answer(response)
