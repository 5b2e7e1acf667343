"""The twin's virtual CAN channel: python-can's virtual bus, each listener's copy of a frame made without deepcopy.

``VirtualBus.send`` gives every other listener of the channel its own copy of the frame, made by
``copy.deepcopy``: the deep copy of the data bytearray goes through the copy protocol and cost ~28 µs a frame,
a copy by Message's constructor ~5 µs (measured on the 2-core machine). The twin's bus and the bus
python-can-remote opens for each connected tester both sit on the channel, so every frame either way was
deep-copied: ~17 % of the twin's CPU in a full WDGA run. ``CopyingVirtualBus`` sends as ``VirtualBus`` does
(same listeners, same stamp, channel and direction on each copy) but copies by the constructor.

python-can-remote builds each tester's bus by name (``can.Bus(**config)``), so the class is registered in
python-can's table of interfaces (``can.interfaces.BACKENDS``) under ``INTERFACE``, in this process only.
"""

from __future__ import annotations

import time
from queue import Full
from typing import Any

import can
from can.interfaces import BACKENDS
from can.interfaces.virtual import VirtualBus

__all__ = ["INTERFACE", "CopyingVirtualBus", "open_channel", "server_config"]

#: the name python-can-remote's server opens each tester's bus with (registered by ``register``)
INTERFACE = "encoder-conformance-virtual"


class CopyingVirtualBus(VirtualBus):
    """A virtual bus whose ``send`` copies each frame by Message's constructor instead of ``deepcopy``."""

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._check_if_open()
        timestamp = msg.timestamp if self.preserve_timestamps else time.time()
        all_sent = True
        for listener in self.channel:
            if listener is self.queue and not self.receive_own_messages:
                continue
            copy = can.Message(
                timestamp=timestamp, arbitration_id=msg.arbitration_id, is_extended_id=msg.is_extended_id,
                is_remote_frame=msg.is_remote_frame, is_error_frame=msg.is_error_frame, channel=self.channel_id,
                dlc=msg.dlc, data=bytearray(msg.data), is_fd=msg.is_fd, is_rx=listener is not self.queue,
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
