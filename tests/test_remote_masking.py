"""python-can-remote to a server on the loopback: the tester's frames go out unmasked, and the server takes them."""

from __future__ import annotations

import socket

import can
from can_remote.websocket import WebSocket

from encoder_conformance.dut.link.remote_masking import unmask_on_loopback


class _Protocol:
    def __init__(self, websocket: object) -> None:
        self._ws = websocket


class _Bus:
    def __init__(self, websocket: object) -> None:
        self.remote_protocol = _Protocol(websocket)


def _client_websocket(sock: socket.socket) -> WebSocket:
    """A websocket playing the client's side (masking) on ``sock``, without the HTTP handshake."""
    websocket = WebSocket(None, "can.binary+json.v1", sock=sock)
    websocket.mask = True  # what python-can-remote sets for a client (``sock is None``)
    return websocket


def test_loopback_client_stops_masking_and_the_server_reads_its_frames() -> None:
    listener = socket.create_server(("127.0.0.1", 0))
    client = socket.create_connection(listener.getsockname())
    served, _ = listener.accept()
    try:
        websocket = _client_websocket(client)
        assert unmask_on_loopback(_Bus(websocket)) is True
        assert websocket.mask is False
        websocket.send(bytearray(b"\x01frame"))
        server = WebSocket(None, "can.binary+json.v1", sock=served)  # python-can-remote's server side
        assert server.read() == bytearray(b"\x01frame")
    finally:
        for sock in (client, served, listener):
            sock.close()


def test_other_hosts_and_other_buses_keep_masking() -> None:
    a, b = socket.socketpair()  # not an IP peer: left as it is
    try:
        websocket = _client_websocket(a)
        assert unmask_on_loopback(_Bus(websocket)) is False
        assert websocket.mask is True
    finally:
        a.close()
        b.close()
    with can.Bus(interface="virtual", channel="masking") as bus:
        assert unmask_on_loopback(bus) is False


def test_masking_is_what_send_frame_consults() -> None:
    """The flag this relies on: python-can-remote's send_frame masks exactly where ``mask`` is set."""
    a, b = socket.socketpair()
    try:
        websocket = _client_websocket(a)
        websocket.send(bytearray(b"\x01x"))
        assert b.recv(64)[1] & 0x80  # mask bit set
        websocket.mask = False
        websocket.send(bytearray(b"\x01x"))
        assert not b.recv(64)[1] & 0x80
    finally:
        a.close()
        b.close()
