"""The simulator host served to other processes (python-can-remote): frames from a remote tester are handled
in the server thread that received them, in arrival order, and the host does not hear its own frames."""

from __future__ import annotations

import queue
import struct
import time
import uuid

import can
import pytest

from encoder_conformance.profile.loader import load_profile
from encoder_conformance.sim.engine.host import SimulatorHost
from tests.sim_rig import MINIMAL, WAIT_S

NODE_ID = 5


@pytest.fixture
def served_host():
    host = SimulatorHost(channel=f"host-test-{uuid.uuid4().hex}")
    host.add_node(load_profile(MINIMAL).profile, NODE_ID, booted=True)
    address, port = host.serve_remote()
    tester = can.Bus(interface="remote", channel=f"ws://{address}:{port}/", receive_own_messages=False)
    yield host, tester
    tester.shutdown()
    host.shutdown()


def _reply(tester: can.BusABC, cob_id: int) -> can.Message | None:
    deadline = time.monotonic() + WAIT_S
    while (left := deadline - time.monotonic()) > 0:
        message = tester.recv(left)
        if message is not None and message.arbitration_id == cob_id:
            return message
    return None


def test_remote_requests_answered_in_order(served_host):
    _, tester = served_host
    for sub in (1, 2, 3, 4):  # 1018h: vendor, product, revision, serial; each answered before the next is sent
        tester.send(can.Message(arbitration_id=0x600 + NODE_ID, data=struct.pack("<BHB4x", 0x40, 0x1018, sub),
                                is_extended_id=False))
        reply = _reply(tester, 0x580 + NODE_ID)
        assert reply is not None, f"no answer to the upload of 1018h sub {sub}"
        assert reply.data[1:4] == struct.pack("<HB", 0x1018, sub), f"answer to another request: {reply}"


def test_listener_is_the_direct_dispatcher_and_hears_no_own_frames(served_host):
    host, _ = served_host
    listeners = host.bus.channel  # the virtual channel's listeners (python-can 4.x: a list of queues)
    adapt = ("python-can's VirtualBus no longer keeps its listeners as a list of queues: the host's direct dispatch "
             "(SimulatorHost._dispatch_in_sender_thread) must be adapted")
    assert host.bus.queue in listeners, adapt
    assert not isinstance(host.bus.queue, queue.Queue), adapt
    heard: list[can.Message] = []
    host.bus.queue._dispatch = heard.append  # type: ignore[union-attr]  # what reaches the host from now on
    host.bus.send(can.Message(arbitration_id=0x77, data=b"\x01", is_extended_id=False))
    assert not heard, "the host heard its own frame"


def test_virtual_channel_copies_as_virtual_bus_send_would():
    """The twin's virtual channel sends as ``VirtualBus.send`` does, without its deep copy (virtual_channel.py): each
    other listener gets a copy of its own, stamped when sent, named by the channel, marked received; the sender
    hears nothing. The host's bus and the buses python-can-remote opens for testers are of that kind."""
    from encoder_conformance.sim.engine.virtual_channel import CopyingVirtualBus, server_config

    channel = f"host-test-{uuid.uuid4().hex}"
    sender = can.Bus(channel=channel, **server_config())  # as python-can-remote's server opens it
    one, two = (can.Bus(interface="virtual", channel=channel) for _ in range(2))
    try:
        assert isinstance(sender, CopyingVirtualBus)
        frame = can.Message(arbitration_id=0x185, data=b"\x01\x02\x03", is_extended_id=False)
        before = time.time()
        sender.send(frame)
        got = [bus.recv(WAIT_S) for bus in (one, two)]
        assert sender.recv(0) is None, "the sender heard its own frame"
        assert all(m is not None for m in got)
        first, second = got
        assert first is not second
        assert first.data is not second.data
        assert first.data is not frame.data
        for message in got:
            assert (message.arbitration_id, bytes(message.data), message.dlc) == (0x185, b"\x01\x02\x03", 3)
            assert message.channel == channel
            assert message.is_rx
            assert not message.is_extended_id
            assert before <= message.timestamp <= time.time()
    finally:
        for bus in (sender, one, two):
            bus.shutdown()


def test_host_and_served_testers_use_the_copying_channel(served_host):
    from encoder_conformance.sim.engine.virtual_channel import CopyingVirtualBus, server_config

    host, _ = served_host
    assert isinstance(host.bus, CopyingVirtualBus)
    assert host._remote is not None
    assert host._remote.config["interface"] == server_config()["interface"]


def test_frames_to_a_remote_tester_are_sent_at_once_and_not_echoed(served_host):
    """Each tester's bus on the server sends the channel's frames at once, in the sender's thread
    (``CopyingVirtualBus.send_directly``): none waits on its queue, the tester hears the host's frames and not
    its own, and a second tester hears the first one's."""
    host, tester = served_host
    other = can.Bus(interface="remote", channel=tester.channel, receive_own_messages=False)
    try:
        deadline = time.monotonic() + WAIT_S
        while len(host._remote.clients) < 2 and time.monotonic() < deadline:  # the second connection served
            time.sleep(0.01)
        buses = [protocol.bus for protocol in host._remote.clients]
        adapt = ("python-can-remote no longer opens each tester's bus before adding it to RemoteServer.clients, "
                 "or VirtualBus keeps no list of queues: CopyingVirtualBus.send_directly must be adapted")
        assert len(buses) == 2, adapt
        assert all(bus._direct in bus.channel and bus.queue not in bus.channel for bus in buses), adapt
        host.bus.send(can.Message(arbitration_id=0x701, data=b"\x05", is_extended_id=False))
        tester.send(can.Message(arbitration_id=0x123, data=b"\x01", is_extended_id=False))
        assert _reply(tester, 0x701) is not None
        assert _reply(other, 0x701) is not None
        assert _reply(other, 0x123) is not None, "a tester's frame did not reach the other tester"
        assert _reply(tester, 0x123) is None, "a tester heard its own frame"
    finally:
        other.shutdown()
