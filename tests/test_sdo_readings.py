"""The SDO open readings (encoder_conformance/open_points/sdo.py): each variant of the twin plays its reading, and the
fuzz oracle accepts what the texts allow (an abort of the open transfer before, or instead of, the answer to a new
initiate) and nothing more."""

from __future__ import annotations

import struct
from collections.abc import Callable

import pytest

from encoder_conformance.cia.cia301 import SdoAbortCode
from encoder_conformance.fuzz.oracle import Exchange, Judge
from encoder_conformance.fuzz.strategies import Request
from encoder_conformance.open_points import sdo as sdo_readings
from encoder_conformance.sim.engine.faults import FaultSet, assemble
from encoder_conformance.sim.engine.sdo_block import BlockEngine
from encoder_conformance.sim.engine.sdo_server import SdoServer
from tests.sdo_server_rig import TEXT, FakeAccess, abort_of, frame, segment

UPLOAD_TEXT = frame(0x40, 0x1008)
UPLOAD_1000 = frame(0x40, 0x1000)


class Timers:
    """Stands in for the node's ``later``: the time-outs armed, run by the test."""

    def __init__(self) -> None:
        self.armed: list[tuple[float, Callable[[], list[bytes]]]] = []

    def __call__(self, delay_s: float, produce: Callable[[], list[bytes]]) -> None:
        self.armed.append((delay_s, produce))

    def expire(self) -> list[bytes]:
        """Run every armed time-out (oldest first); the frames they produced."""
        armed, self.armed = self.armed, []
        return [f for _, produce in armed for f in produce()]


def _server(variant: str, timers: Timers | None = None, block: bool = False) -> SdoServer:
    faults = FaultSet([variant])
    engine = assemble(BlockEngine, faults) if block else None
    return assemble(SdoServer, faults)(FakeAccess(), engine, later=timers, timeout_s=1.0)


def _open_upload(server: SdoServer) -> None:
    assert server.respond(UPLOAD_TEXT)[0][0] == 0x41
    assert server.respond(segment(0x60))[0][0] == 0x00


def test_every_sdo_reading_names_its_source_and_modules():
    for reading in sdo_readings.READINGS:
        assert reading.source.startswith("CiA 301 v4.2.0 §"), reading.point
        assert len(reading.readings) >= 2, reading.point
        assert reading.modules, reading.point


def test_interrupt_aborts_open_transfer_then_serves():
    server = _server("interrupt_aborts_open_transfer")
    _open_upload(server)
    aborted, answer = server.respond(UPLOAD_1000)
    assert abort_of(aborted)[:2] == (0x1008, 0)
    assert answer[:4] == bytes.fromhex("43001000")
    assert server.respond(segment(0x70))[0][0] == 0x80  # the aborted transfer does not go on


def test_interrupt_consumed_by_open_transfer_answers_only_the_abort():
    server = _server("interrupt_consumed_by_open_transfer")
    _open_upload(server)
    assert [abort_of(f) for f in server.respond(UPLOAD_1000)] == [(0x1008, 0, SdoAbortCode.COMMAND_SPECIFIER)]
    assert server.respond(UPLOAD_1000)[0][:4] == bytes.fromhex("43001000")  # sent again: served


def test_left_open_transfer_times_out_only_without_a_request():
    timers = Timers()
    server = _server("left_open_transfer_times_out", timers)
    _open_upload(server)
    assert len(timers.armed) == 2
    assert timers.armed[0][0] == pytest.approx(0.025)
    assert [abort_of(f) for f in timers.expire()] == [(0x1008, 0, SdoAbortCode.TIMEOUT)]  # the stale one: nothing
    _open_upload(server)
    server.respond(UPLOAD_1000)  # a request in between: the time-out armed before it is stale
    assert timers.expire() == []


def test_slow_subblock_timeout_acknowledges_after_the_time_out():
    timers = Timers()
    server = _server("slow_subblock_timeout", timers, block=True)
    assert server.respond(struct.pack("<BHBI", 0xC6, 0x1017, 0, 2))[0][0] == 0xA4  # initiate block download
    assert server.respond(bytes([0x82]) + b"\x01\x02" + bytes(5)) == []  # segment 2 first: ignored
    assert timers.armed[-1][0] == 1.0
    assert timers.expire() == [bytes([0xA2, 0, 127]) + bytes(5)]  # ackseq 0: nothing received in order
    assert server.respond(bytes([0x81]) + b"\x01\x02" + bytes(5))[0][:2] == b"\xa2\x01"


def test_default_block_engine_acknowledges_at_once():
    server = SdoServer(FakeAccess(), BlockEngine)
    server.respond(struct.pack("<BHBI", 0xC6, 0x1017, 0, 2))
    assert server.respond(bytes([0x82]) + bytes(7))[0][:2] == b"\xa2\x00"


# -- the fuzz oracle ---------------------------------------------------------------------------------------
def _judge(*pairs: tuple[bytes, list[bytes]]) -> list[str]:
    return Judge().judge([Exchange(Request(request), list(replies)) for request, replies in pairs])


OPENED = (UPLOAD_TEXT, [struct.pack("<BHBI", 0x41, 0x1008, 0, len(TEXT))])
ABORT_OPEN = struct.pack("<BHBI", 0x80, 0x1008, 0, SdoAbortCode.GENERAL_ERROR)
ANSWER_1000 = frame(0x43, 0x1000, 0, bytes.fromhex("96010200"))


def test_oracle_accepts_an_abort_of_the_open_transfer_then_the_answer():
    assert _judge(OPENED, (UPLOAD_1000, [ABORT_OPEN, ANSWER_1000])) == []
    # attributed to the request before (it fits an initiate of the same entry): moved to the next initiate
    assert _judge(OPENED, (UPLOAD_1000, [])) != []
    assert _judge((OPENED[0], [*OPENED[1], ABORT_OPEN]), (UPLOAD_1000, [ANSWER_1000])) == []


def test_oracle_accepts_the_abort_of_the_open_transfer_alone():
    assert _judge(OPENED, (UPLOAD_1000, [ABORT_OPEN]), (segment(0x60), [abort_frame_for(0x1008)])) == []


def abort_frame_for(index: int) -> bytes:
    return struct.pack("<BHBI", 0x80, index, 0, SdoAbortCode.COMMAND_SPECIFIER)


def test_oracle_refuses_an_abort_naming_neither_transfer():
    other = struct.pack("<BHBI", 0x80, 0x2000, 0, SdoAbortCode.GENERAL_ERROR)
    assert _judge(OPENED, (UPLOAD_1000, [other, ANSWER_1000]))
    assert _judge(OPENED, (UPLOAD_1000, [other]))


def test_oracle_refuses_two_answers_without_an_open_transfer():
    assert _judge((UPLOAD_1000, [ABORT_OPEN, ANSWER_1000]))


def test_oracle_pulls_back_an_answer_that_came_after_the_next_request():
    """The open transfer's own entry asked again: its abort, then (after the next request went out) its answer."""
    again = struct.pack("<BHBI", 0x41, 0x1008, 0, len(TEXT))
    first_segment = bytes([0x00]) + TEXT[:7]
    assert _judge(OPENED, (UPLOAD_TEXT, [ABORT_OPEN]), (segment(0x60), [again, first_segment])) == []
    assert _judge(OPENED, (UPLOAD_TEXT, [ABORT_OPEN]), (segment(0x60), [ABORT_OPEN, first_segment]))  # twice


def test_oracle_pulls_back_across_a_client_abort():
    """The shifted replies run past a client's abort (which owes none): each goes back to the request before."""
    refused = struct.pack("<BHBI", 0x80, 0x1008, 0, SdoAbortCode.WRITE_RO)
    write_again = frame(0x23, 0x1008, 0, b"\x00\x00\x00\x00")
    no_transfer = abort_frame_for(0)
    assert _judge(OPENED, (write_again, [ABORT_OPEN]), (segment(0x00), [refused]),
                  (struct.pack("<BHBI", 0x80, 0, 0, SdoAbortCode.TIMEOUT), [no_transfer])) == []


def test_oracle_gives_the_answer_to_the_repeated_request():
    """An initiate taken by the open transfer (its abort only), then sent again and answered: the answer is the
    repeated request's, not the first one's."""
    assert _judge(OPENED, (UPLOAD_1000, []), (UPLOAD_1000, [])) != []
    opened = (OPENED[0], [*OPENED[1], ABORT_OPEN])  # the abort fits the opening initiate: attributed there
    assert _judge(opened, (UPLOAD_1000, [ANSWER_1000]), (UPLOAD_1000, [])) == []


def test_oracle_same_entry_taken_by_the_open_transfer_then_asked_again():
    """The open transfer's entry asked again, taken by the open transfer (its abort only), asked a third time and
    answered: nothing is moved, each request has its own reply."""
    again = struct.pack("<BHBI", 0x41, 0x1008, 0, len(TEXT))
    assert _judge(OPENED, (UPLOAD_TEXT, [abort_frame_for(0x1008)]), (UPLOAD_TEXT, [again]), (UPLOAD_1000, [])) != []
    assert _judge(OPENED, (UPLOAD_TEXT, [abort_frame_for(0x1008)]), (UPLOAD_TEXT, [again])) == []


def test_oracle_moves_the_replies_on_after_a_request_taken_by_the_open_transfer():
    """The abort of the open transfer went to its own initiate (same entry); the request after it drew nothing and
    each later reply went one request too early: they move on by one."""
    opened = (OPENED[0], [*OPENED[1], ABORT_OPEN])
    no_transfer = abort_frame_for(0)
    first, second = frame(0x20, 0, 0), segment(0x60)
    assert _judge(opened, (first, [no_transfer]), (second, [abort_frame_for(0x2000)]), (segment(0x70), [])) == []
