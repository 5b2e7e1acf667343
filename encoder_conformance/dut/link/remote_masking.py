"""python-can-remote on the loopback: the tester's websocket frames go out unmasked.

A websocket client masks every frame it sends (RFC 6455 §5.3), to keep a caching proxy between browser and
server from being poisoned. python-can-remote masks and unmasks in Python, byte by byte: measured on the 2-core
machine, ~5 µs of the tester's CPU per frame sent and ~10 % of the twin's CPU in a run (the server's unmasking
loop, and one more socket read per frame for the masking key). On the loopback there is no proxy to protect,
and python-can-remote's server reads a frame's mask bit and takes unmasked frames as they are
(``WebSocket.read_frame``). So where the server is on this host, the client's websocket is told not to mask:
its own ``mask`` flag, which python-can-remote sets from the side it plays (``sock is None``: a client) and which
``WebSocket.send_frame`` consults for every frame. Nothing of the library's code is replaced; a server on
another host keeps masked frames. ``test_remote_masking`` checks the attribute is still there and still obeyed.
"""

from __future__ import annotations

import ipaddress
import socket
from typing import Any

__all__ = ["unmask_on_loopback"]


def _is_loopback(sock: socket.socket) -> bool:
    try:
        host = sock.getpeername()[0]
    except (OSError, IndexError, TypeError):
        return False
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def unmask_on_loopback(bus: Any) -> bool:
    """Stop ``bus`` (a python-can-remote ``RemoteBus``) masking its frames where its server is on this host's
    loopback; True where it did. Any other bus, or a RemoteBus whose internals are not as expected, is left
    as it is."""
    websocket = getattr(getattr(bus, "remote_protocol", None), "_ws", None)
    sock = getattr(websocket, "socket", None)
    if websocket is None or getattr(websocket, "mask", None) is not True or not isinstance(sock, socket.socket):
        return False
    if not _is_loopback(sock):
        return False
    websocket.mask = False
    return True
