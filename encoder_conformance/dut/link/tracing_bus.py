"""The tester's bus wrapper: traces what it sends, and turns a lost bus into one clear state.

Same idea as python-can's ThreadSafeBus proxy: everything else is forwarded unchanged, so
canopen's Network and Notifier use it like the real bus. On top of that:

- every transmitted frame is copied into the FrameLog (both directions traced), and every frame, sent or
  received, names the channel it was on (the bus's, where the interface leaves it unnamed: python-can's
  trace writers would label it ``vcan0``);
- the first send or receive error (connection closed, interface gone) closes the FrameLog with
  the reason: every wait then raises BusLostError at once, and later receives idle quietly
  instead of raising in a loop (python-can's Notifier would call them again and again);
- ``shutdown`` has a bound: python-can-remote's shutdown waits for the server's close frame
  forever when the server is frozen (measured: a run hung 25 min).
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
from typing import Any

import can

from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.link.time_budget import BUDGET
from encoder_conformance.errors import BusLostError

log = logging.getLogger(__name__)

#: a socket-based interface (python-can-remote) whose peer stalls mid-frame raises after this long
SOCKET_TIMEOUT_S = 3.0
SHUTDOWN_TIMEOUT_S = 1.0


def _channel_of(bus: can.BusABC) -> str | int | None:
    """The channel a python-can bus was opened on (socketcan, remote: ``channel``; virtual: ``channel_id``)."""
    for name in ("channel", "channel_id"):
        value = getattr(bus, name, None)
        if isinstance(value, (str, int)) and value != "":
            return value
    return None


class TracingBus:
    """Forwards to ``bus``; ``send`` also records the frame as a tester transmission."""

    def __init__(self, bus: can.BusABC, log: FrameLog, channel: str | int | None = None) -> None:
        self._bus = bus
        self._log = log
        self._channel = channel if channel is not None else _channel_of(bus)
        self._idle = threading.Event()  # never set: a lost bus's recv waits on it for its timeout
        sock = getattr(bus, "socket", None)
        if isinstance(sock, socket.socket):  # bound blocking reads/writes of network interfaces
            with contextlib.suppress(OSError):
                sock.settimeout(SOCKET_TIMEOUT_S)

    @property
    def lost(self) -> str | None:
        return self._log.closed_reason

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if self.lost:
            raise BusLostError(self.lost)
        # logged before it goes out: the device's answer can arrive (on the receive thread) before send()
        # returns, and the log and the traces keep the order the frames had on the bus
        self._log.record_sent(msg, self._channel)
        try:
            with BUDGET.booking("send"):  # the interface's time to take the frame: bus traffic, not the tester's
                self._bus.send(msg, timeout)
        except (can.CanError, OSError, ValueError, RuntimeError) as exc:
            reason = f"the CAN bus failed on send: {type(exc).__name__}: {exc}"
            self._log.close(reason)
            raise BusLostError(reason) from None

    def recv(self, timeout: float | None = None) -> can.Message | None:
        if self.lost:
            self._idle.wait(timeout if timeout is not None else 0.1)
            return None
        try:
            msg = self._bus.recv(timeout)
        except Exception as exc:  # any interface error ends the bus for this run
            self._log.close(f"the CAN bus failed on receive: {type(exc).__name__}: {exc}")
            return None
        if msg is not None:
            # a received frame is another node's: the tester's own are logged by send(). A vcan (the kernel's
            # or a user-space one) marks frames of other programs on the host (a firmware simulator) as
            # locally sent, which python-can's socketcan reports as is_rx False
            msg.is_rx = True
            if msg.channel is None:
                msg.channel = self._channel
        return msg

    def __getattr__(self, name: str) -> Any:
        return getattr(self._bus, name)

    def shutdown(self) -> None:
        """Shut the interface down, waiting at most SHUTDOWN_TIMEOUT_S (then abandon it)."""
        finished = threading.Event()

        def close() -> None:
            with contextlib.suppress(Exception):  # the server may already be gone
                self._bus.shutdown()
            finished.set()

        threading.Thread(target=close, name="bus-shutdown", daemon=True).start()
        if not finished.wait(SHUTDOWN_TIMEOUT_S):
            log.warning("the CAN interface did not shut down within %.1f s; abandoned", SHUTDOWN_TIMEOUT_S)
            sock = getattr(self._bus, "socket", None)
            if isinstance(sock, socket.socket):
                with contextlib.suppress(OSError):
                    sock.close()
