"""The SDO channel of a node: which requests reach the SDO server, and what goes back on the bus.

CiA 301 §7.3.2.2: SDO is served in pre-operational and operational only; a transfer in progress
ends when the node enters stopped. Faults that break the channel are the small classes below.
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.cia.cia301 import SDO_ABORT, SDO_RESPONSE_BASE
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks
from encoder_conformance.sim.engine.nmt import NmtState, sdo_allowed
from encoder_conformance.sim.engine.sdo_server import SdoServer


class SdoChannel:
    """Receives SDO requests on 600h + node-id and answers on 580h + node-id."""

    def __init__(self, server: SdoServer, send: Callable[[int, bytes], None], state: Callable[[], NmtState | None],
                 node_id: Callable[[], int]) -> None:
        self._server = server
        self._send = send
        self._state = state
        self._node_id = node_id

    def register(self, hooks: NodeHooks) -> None:
        hooks.halted.append(self._server.reset)
        hooks.state.append(self._on_state)

    def _on_state(self, state: NmtState) -> None:
        if state is NmtState.STOPPED:
            self._server.reset()  # a transfer in progress cannot continue in stopped

    def serves(self, request: bytes) -> bool:
        state = self._state()
        return state is not None and sdo_allowed(state)

    def answer(self, response: bytes) -> bytes | None:
        return response

    def on_request(self, request: bytes) -> None:
        if not self.serves(request):
            return
        self.send_frames(self._server.respond(request))  # one response, none, or a block's segments

    def send_frames(self, frames: list[bytes]) -> None:
        """Send the server's frames: the answers to a request, or what a time-out of the server's own produced."""
        for frame in frames:
            response = self.answer(frame)
            if response is not None:
                self._send(SDO_RESPONSE_BASE + self._node_id(), response)


@breaks(SdoChannel, "no_sdo_response")
class DeafSdoChannel(SdoChannel):
    def serves(self, request: bytes) -> bool:
        return False


@breaks(SdoChannel, "sdo_in_stopped")
class SdoInStopped(SdoChannel):
    def serves(self, request: bytes) -> bool:
        return self._state() is not None or super().serves(request)


#: how late ``sdo_late_in_stopped`` answers: after the longest SDO silence window any shipped profile can get before
#: its measurement (SIKO: sdo_response_max_ms 250 + the unmeasured 50 ms margin), so after the window on every profile
LATE_ANSWER_S = 0.33


@breaks(SdoChannel, "sdo_late_in_stopped")
class SdoLateInStopped(SdoChannel):
    """A request in stopped is answered, but only LATE_ANSWER_S later (after the tester's silence window)."""

    def on_request(self, request: bytes) -> None:
        state = self._state()
        later = self._server._later  # the node's delayed send, which the server's own time-outs use
        if state is not NmtState.STOPPED or later is None:
            super().on_request(request)
            return
        frames = self._server.respond(request)
        later(LATE_ANSWER_S, lambda: frames)


@breaks(SdoChannel, "ignore_unknown_command")
class IgnoresUnknownCommands(SdoChannel):
    def serves(self, request: bytes) -> bool:
        reserved_or_block = bool(request) and request[0] >> 5 in (5, 6, 7)
        return not reserved_or_block and super().serves(request)


@breaks(SdoChannel, "abort_without_multiplexer")
class AbortWithoutMultiplexer(SdoChannel):
    """Abort frames carry index 0000h sub 00, as canopen's own client sends them (issue #377)."""

    def answer(self, response: bytes) -> bytes | None:
        if response[0] == SDO_ABORT:
            response = response[:1] + bytes(3) + response[4:]
        return super().answer(response)
