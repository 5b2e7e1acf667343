"""FrameLog: listeners (per-test trace writers) run before waiters wake, and a failing listener is not a
lost bus (a trace writer closed at a test's teardown ended runs as 'could not test' on a loaded PC); every
frame of a trace names the channel it was on."""

from __future__ import annotations

import threading

import can
import pytest

from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.link.tracing_bus import TracingBus
from encoder_conformance.plugin.bus_trace import BusTrace


class Recorder(can.Listener):
    def __init__(self) -> None:
        self.seen: list[can.Message] = []

    def on_message_received(self, msg: can.Message) -> None:
        self.seen.append(msg)


class ClosedTrace(can.Listener):
    def on_message_received(self, msg: can.Message) -> None:
        raise ValueError("I/O operation on closed file.")


def test_a_failing_listener_is_not_a_lost_bus():
    log = FrameLog()
    log.add_listener(ClosedTrace())
    mark = log.mark()
    log.on_message_received(can.Message(arbitration_id=0x181, data=b"\x01"))
    assert log.closed_reason is None
    assert len(log.since(mark)) == 1


def test_listener_has_the_frame_before_the_waiter_wakes():
    log, recorder = FrameLog(), Recorder()
    log.add_listener(recorder)
    for n in range(50):  # many rounds: the receive thread and the waiter race each time
        mark = log.mark()
        frame = can.Message(arbitration_id=0x581, data=bytes([n]))
        threading.Thread(target=log.on_message_received, args=(frame,)).start()
        assert log.wait_for(lambda m, f=frame: m is f, 2.0, mark) is frame
        assert recorder.seen[-1] is frame, "the trace misses the frame the test already acted on"


def test_a_removed_listener_is_never_called_again():
    log, recorder = FrameLog(), Recorder()
    log.add_listener(recorder)
    log.on_message_received(can.Message(arbitration_id=0x181))
    log.remove_listener(recorder)
    log.on_message_received(can.Message(arbitration_id=0x182))
    assert [m.arbitration_id for m in recorder.seen] == [0x181]


class UnnamedBus(can.BusABC):
    """An interface whose frames name no channel (python-can-remote's binary frames): one frame to receive."""

    def __init__(self) -> None:
        super().__init__(channel=None)
        self.pending = [can.Message(arbitration_id=0x581, data=b"\x43\x00\x10\x00")]

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        pass

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        return (self.pending.pop() if self.pending else None), False


@pytest.mark.parametrize("opened", ["socketcan-like", "unnamed"])
def test_the_candump_trace_names_the_channel_of_every_frame(tmp_path, opened):
    """The tester's own frames and the device's carry the channel the run used (``--can-channel can0``): the
    trace once labelled the tester's frames ``vcan0`` (python-can's writer's default) and the device's ``can0``."""
    log = FrameLog()
    trace = BusTrace(tmp_path / "traces" / "t.asc")
    log.add_listener(trace)
    if opened == "socketcan-like":  # a bus that names received frames itself (python-can's virtual, as socketcan)
        bus: can.BusABC = can.Bus(interface="virtual", channel="can0")
        device = can.Bus(interface="virtual", channel="can0")
        tester = TracingBus(bus, log)  # the channel read from the bus
    else:
        bus = device = UnnamedBus()
        tester = TracingBus(bus, log, "can0")  # the channel the run was given
    try:
        tester.send(can.Message(arbitration_id=0x605, data=b"\x40\x00\x10\x00\x00\x00\x00\x00"))
        if device is not bus:
            device.send(can.Message(arbitration_id=0x585, data=b"\x43\x00\x10\x00"))
        received = tester.recv(2.0)
        assert received is not None
        log.on_message_received(received)
    finally:
        bus.shutdown()
        device.shutdown()
    trace.write()
    lines = (tmp_path / "traces" / "t.log").read_text().splitlines()
    assert [line.split()[1] for line in lines] == ["can0", "can0"]
    assert [line.split()[3] for line in lines] == ["T", "R"]
