"""The twin's virtual CAN channel: python-can's virtual bus, each listener's copy of a frame made without deepcopy.

``VirtualBus.send`` gives every other listener of the channel its own copy of the frame, made by
``copy.deepcopy``: the deep copy of the data bytearray goes through the copy protocol and cost ~28 µs a frame,
a copy by Message's constructor ~5 µs (measured on the 2-core machine). The twin's bus and the bus
python-can-remote opens for each connected tester both sit on the channel, so every frame either way was
deep-copied: ~17 % of the twin's CPU in a full WDGA run. ``CopyingVirtualBus`` sends as ``VirtualBus`` does
(same listeners, same stamp, channel and direction on each copy) but copies by the constructor.

python-can-remote builds each tester's bus by name (``can.Bus(**config)``), so the class is registered in
python-can's table of interfaces (``can.interfaces.BACKENDS``) under ``INTERFACE``, in this process only.

A frame for a tester goes out on its websocket in the thread that sent it (``send_directly``): python-can-remote's
server otherwise puts it on the tester's bus queue, where a thread of its own takes it and sends it, one thread
switch more per frame the twin sends. Its thread stays and still sends anything left on the queue.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable
from queue import Full, Queue
from typing import Any, cast

import can
from can.interfaces import BACKENDS
from can.interfaces.virtual import VirtualBus, channels_lock

__all__ = ["INTERFACE", "CopyingVirtualBus", "open_channel", "server_config"]

#: the name python-can-remote's server opens each tester's bus with (registered by ``register``)
INTERFACE = "encoder-conformance-virtual"


class _SendAtOnce:
    """Stands in for a tester's queue in the channel's list of listener queues: ``put`` sends the frame at once."""

    def __init__(self, send: Callable[[can.Message], None]) -> None:
        self._send = send

    def put(self, msg: can.Message, block: bool = True, timeout: float | None = None) -> None:
        with contextlib.suppress(OSError):  # the tester went away: its connection's own thread ends the connection
            self._send(msg)


class CopyingVirtualBus(VirtualBus):
    """A virtual bus whose ``send`` copies each frame by Message's constructor instead of ``deepcopy``."""

    _direct: _SendAtOnce | None = None

    def send_directly(self, send: Callable[[can.Message], None]) -> None:
        """The frames others put on this bus go to ``send`` at once, in the sender's thread, instead of onto
        this bus's queue for ``recv``. DESIGN: leans on VirtualBus keeping its listeners as a list of queues
        (python-can 4.x), as the host's own dispatch does; ``test_sim_host`` checks it."""
        direct = _SendAtOnce(send)
        # cast: python-can types the list as holding Queues; the stand-in has the one method it calls, put
        with channels_lock:
            self.channel[self.channel.index(self.queue)] = cast("Queue[can.Message]", direct)
        self._direct = direct

    def shutdown(self) -> None:
        direct = self._direct
        if direct is not None and self._open:  # VirtualBus.shutdown takes its own queue off the channel
            with channels_lock:
                self.channel[self.channel.index(cast("Queue[can.Message]", direct))] = self.queue
            self._direct = None
        super().shutdown()

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._check_if_open()
        timestamp = msg.timestamp if self.preserve_timestamps else time.time()
        all_sent = True
        own = self._direct or self.queue
        for listener in self.channel:
            if listener is own and not self.receive_own_messages:
                continue
            copy = can.Message(
                timestamp=timestamp, arbitration_id=msg.arbitration_id, is_extended_id=msg.is_extended_id,
                is_remote_frame=msg.is_remote_frame, is_error_frame=msg.is_error_frame, channel=self.channel_id,
                dlc=msg.dlc, data=bytearray(msg.data), is_fd=msg.is_fd, is_rx=listener is not own,
                bitrate_switch=msg.bitrate_switch, error_state_indicator=msg.error_state_indicator, check=False)
            try:
                listener.put(copy, block=True, timeout=timeout)
            except Full:
                all_sent = False
        if not all_sent:
            raise can.CanOperationError("Could not send message to one or more recipients")


def open_channel(channel: str, **kwargs: Any) -> CopyingVirtualBus:
    """The twin's own bus on ``channel``: what ``can.Bus(interface="virtual", ...)`` opens (python-can's
    configuration sources read the same way), as a ``CopyingVirtualBus``."""
    config = dict(can.util.load_config(config={**kwargs, "interface": "virtual", "channel": channel}))
    del config["interface"]
    return CopyingVirtualBus(config.pop("channel"), **config)


def server_config() -> dict[str, Any]:
    """What python-can-remote's server opens each tester's bus with: ``CopyingVirtualBus``, by a name registered in
    python-can's table of interfaces in this process. python-can's configuration files are not read for it
    (``ignore_config``: its check of an interface's name uses the table as it was at import, and a file's adapter
    settings mean nothing to a virtual channel)."""
    BACKENDS.setdefault(INTERFACE, (__name__, CopyingVirtualBus.__name__))
    return {"interface": INTERFACE, "ignore_config": True}
