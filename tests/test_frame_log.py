"""FrameLog: listeners (per-test trace writers) run before waiters wake, and a failing listener is not a
lost bus (a trace writer closed at a test's teardown ended runs as 'could not test' on a loaded PC)."""

from __future__ import annotations

import threading

import can

from encoder_conformance.dut.frames import FrameLog


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
