"""A bus wrapper that copies every transmitted frame into the FrameLog (both directions traced).

Same idea as python-can's ThreadSafeBus proxy: everything else is forwarded unchanged, so
canopen's Network and Notifier use it like the real bus.
"""

from __future__ import annotations

import contextlib
from typing import Any

import can

from .frames import FrameLog


class TracingBus:
    """Forwards to ``bus``; ``send`` also records the frame as a tester transmission."""

    def __init__(self, bus: can.BusABC, log: FrameLog) -> None:
        self._bus = bus
        self._log = log

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._bus.send(msg, timeout)
        self._log.record_sent(msg)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._bus, name)

    def shutdown(self) -> None:
        with contextlib.suppress(OSError):  # python-can-remote: the server may already be gone
            self._bus.shutdown()
