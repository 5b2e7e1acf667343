"""Open reading sdo-initiate-reserved-bits: an initiate request with bits set that CiA 301 says are always 0 (upload
41h-5Fh, download with bit 4) may be served as if they were 0, or refused with 05040001h naming any multiplexer
(CANopenNode: the previous transfer's). The reply matching, the fuzz attribution and judge accept both and nothing
more: a valid initiate's answer or abort still echoes its multiplexer, and a second reply is still one too many. The
variant initiate_reserved_bits_refused plays the refusal."""

from __future__ import annotations

import struct

import pytest

from encoder_conformance.cia.cia301 import SdoAbortCode
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.fuzz import strategies as fz
from encoder_conformance.fuzz.attribution import attribute
from encoder_conformance.fuzz.oracle import Exchange, Judge
from encoder_conformance.open_points import all_readings
from encoder_conformance.sim.engine.faults import FaultSet, assemble
from encoder_conformance.sim.engine.sdo_server import SdoServer
from tests import sim_rig
from tests.sdo_server_rig import TEXT, FakeAccess, abort_of, frame, segment
from tests.test_sdo_fuzz_runner import _runner as fuzz_runner

rig = sim_rig.rig  # the shared fixture
VARIANT = "initiate_reserved_bits_refused"
INVALID = SdoAbortCode.COMMAND_SPECIFIER

UPLOAD_1000 = frame(0x40, 0x1000)
ANSWER_1000 = frame(0x43, 0x1000, 0, bytes.fromhex("96010200"))
RESERVED_UPLOAD_1001 = frame(0x4A, 0x1001)  # ccs 2, bits 3 and 1 set
RESERVED_DOWNLOAD_1017 = frame(0x3B, 0x1017, 0, b"\x01\x00")  # ccs 1 with bit 4 set (expedited, 2 bytes)
UPLOAD_1008 = frame(0x40, 0x1008)
SEGMENTED_1008 = struct.pack("<BHBI", 0x41, 0x1008, 0, len(TEXT))


def _abort(index: int, sub: int, code: int) -> bytes:
    return struct.pack("<BHBI", 0x80, index, sub, code)


STALE_REFUSAL = _abort(0x1000, 0, INVALID)  # refuses RESERVED_UPLOAD_1001, naming the previous request's entry


def _hex(value: object) -> str | None:
    return value.hex(" ").upper() if isinstance(value, bytes) else None


# -- matching a reply to its request (dut/sdo/sdo_frames.py) -----------------------------------------------------------
@pytest.mark.parametrize(("request_", "reply", "fits"), [
    (RESERVED_UPLOAD_1001, STALE_REFUSAL, True),  # refused as an invalid command: any multiplexer
    (RESERVED_UPLOAD_1001, _abort(0, 0, INVALID), True),
    (RESERVED_DOWNLOAD_1017, STALE_REFUSAL, True),
    (RESERVED_UPLOAD_1001, _abort(0x1000, 0, SdoAbortCode.NO_OBJECT), False),  # another code: served, so echoed
    (RESERVED_UPLOAD_1001, _abort(0x1001, 0, SdoAbortCode.NO_OBJECT), True),
    (RESERVED_UPLOAD_1001, frame(0x4F, 0x1000, 0, b"\x01"), False),  # served: the answer echoes the multiplexer
    (RESERVED_UPLOAD_1001, frame(0x4F, 0x1001, 0, b"\x01"), True),
    (UPLOAD_1000, _abort(0x1001, 0, INVALID), False),  # a valid initiate: its abort echoes its multiplexer
    (frame(0x2B, 0x1017), _abort(0x1000, 0, INVALID), False),  # download, bit 4 clear
], ids=_hex)
def test_answers(request_, reply, fits):
    assert sdo_frames.answers(request_, reply) is fits


def test_reserved_bits_per_initiate():
    assert [sdo_frames.reserved_bits_set(frame(c)) for c in (0x40, 0x41, 0x5F, 0x60, 0x2F, 0x30, 0x23, 0x80, 0xE1)] \
        == [False, True, True, False, False, True, False, False, False]
    assert not sdo_frames.reserved_bits_set(b"")


# -- the fuzz judge and attribution ---------------------------------------------------------------------------------
def _judge(*pairs: tuple[bytes, list[bytes]]) -> list[str]:
    return Judge().judge([Exchange(fz.Request(request), list(replies)) for request, replies in pairs])


def _attributed(*steps: tuple[bytes, list[bytes]]) -> list[Exchange]:
    """The exchanges as the attribution makes them from the bus: each request, then the replies it drew."""
    events = [event for request, replies in steps for event in [(True, request), *((False, r) for r in replies)]]
    exchanges, stray = attribute([fz.Request(request) for request, _ in steps], events)
    assert stray == []
    return exchanges


def test_judge_accepts_either_reading():
    assert _judge((UPLOAD_1000, [ANSWER_1000]), (RESERVED_UPLOAD_1001, [STALE_REFUSAL])) == []  # refused
    assert _judge((RESERVED_UPLOAD_1001, [frame(0x4F, 0x1001, 0, b"\x00")])) == []  # served as 40h
    assert _judge((RESERVED_UPLOAD_1001, [_abort(0x1001, 0, SdoAbortCode.NO_OBJECT)])) == []  # served, aborted


@pytest.mark.parametrize(("pairs", "words"), [
    ([(RESERVED_UPLOAD_1001, [_abort(0x1000, 0, SdoAbortCode.NO_OBJECT)])], "only 05040001h"),  # another code
    ([(RESERVED_UPLOAD_1001, [frame(0x4F, 0x1000, 0, b"\x00")])], "does not echo"),  # served: echoes
    ([(UPLOAD_1000, [_abort(0x2000, 0, INVALID)])], "does not echo"),  # a valid initiate, never refused so
    ([(RESERVED_UPLOAD_1001, [STALE_REFUSAL, STALE_REFUSAL])], "2 replies"),
    ([(RESERVED_UPLOAD_1001, [STALE_REFUSAL, frame(0x4F, 0x1001, 0, b"\x00")])], "2 replies"),  # both readings
])
def test_judge_stays_strict(pairs, words):
    problems = _judge(*pairs)
    assert any(words in p for p in problems), problems


def test_the_stale_refusal_is_not_booked_against_the_previous_request():
    """CANopenNode's abort names the entry the previous request asked for: it is the reserved request's answer."""
    exchanges = _attributed((UPLOAD_1000, [ANSWER_1000]), (RESERVED_UPLOAD_1001, [STALE_REFUSAL]))
    assert [e.replies for e in exchanges] == [[ANSWER_1000], [STALE_REFUSAL]]
    assert Judge().judge(exchanges) == []


def test_a_refusal_sent_twice_is_still_two_replies():
    exchanges = _attributed((UPLOAD_1000, [ANSWER_1000]), (RESERVED_UPLOAD_1001, [STALE_REFUSAL, STALE_REFUSAL]))
    assert any("2 replies" in p for p in Judge().judge(exchanges))


def test_interleaved_refusal_during_an_open_transfer():
    """A reserved-bit initiate while a segmented upload is open: refused naming the open transfer, which ends; the
    segments meant for it are then aborted."""
    segment_abort = _abort(0x1008, 0, INVALID)
    no_transfer = _abort(0, 0, INVALID)
    exchanges = _attributed((UPLOAD_1008, [SEGMENTED_1008]), (RESERVED_UPLOAD_1001, [segment_abort]),
                            (segment(0x60), [no_transfer]))
    assert [len(e.replies) for e in exchanges] == [1, 1, 1]
    assert Judge().judge(exchanges) == []


def test_interleaved_refusal_after_an_expedited_initiate():
    """The issue's case: the first initiate closed at once (no transfer open), the refusal names its entry."""
    exchanges = _attributed((UPLOAD_1000, [ANSWER_1000]), (RESERVED_UPLOAD_1001, [STALE_REFUSAL]),
                            (segment(0x60), [_abort(0, 0, INVALID)]))
    assert [e.replies for e in exchanges][:2] == [[ANSWER_1000], [STALE_REFUSAL]]
    assert Judge().judge(exchanges) == []


# -- the variant ----------------------------------------------------------------------------------------------------
def _server(*names: str) -> SdoServer:
    return assemble(SdoServer, FaultSet([VARIANT, *names]))(FakeAccess())


def test_the_reading_names_its_variant():
    reading = next(r for r in all_readings() if r.point == "sdo-initiate-reserved-bits")
    assert reading.variant == VARIANT
    assert reading.source.startswith("CiA 301 v4.2.0 §7.2.4.3.6")
    assert reading.modules == ("test_sdo_fuzz",)


def test_variant_refuses_with_the_previous_multiplexer():
    server = _server()
    assert [abort_of(f) for f in server.respond(RESERVED_UPLOAD_1001)] == [(0, 0, INVALID)]  # none before
    assert server.respond(UPLOAD_1000) == [ANSWER_1000]
    assert [abort_of(f) for f in server.respond(RESERVED_UPLOAD_1001)] == [(0x1000, 0, INVALID)]
    assert [abort_of(f) for f in server.respond(RESERVED_DOWNLOAD_1017)] == [(0x1000, 0, INVALID)]
    assert server.respond(frame(0x2B, 0x1017, 0, b"\x01\x00"))[0][:4] == bytes.fromhex("60171000")  # bit 4 clear


def test_variant_ends_an_open_transfer():
    server = _server()
    assert server.respond(UPLOAD_1008) == [SEGMENTED_1008]
    assert [abort_of(f) for f in server.respond(RESERVED_UPLOAD_1001)] == [(0x1008, 0, INVALID)]
    assert abort_of(server.respond(segment(0x60))[0])[2] == INVALID  # no transfer open any more


def test_default_twin_serves_reserved_bits_as_zero():
    assert SdoServer(FakeAccess()).respond(RESERVED_UPLOAD_1001) == [frame(0x4F, 0x1001, 0, b"\x00")]


# -- the fuzz runner against the twin ---------------------------------------------------------------------------------
RESERVED_EXAMPLES = [
    (fz.Request(UPLOAD_1000), fz.Request(frame(0x5F, 0x1018, 1))),
    (fz.Request(frame(0x41, 0xF000, 3)),),  # a reserved index: reading A aborts 06020000h, reading B 05040001h
    (fz.Request(UPLOAD_1008), fz.Request(frame(0x41, 0x1000)), fz.Request(segment(0x60))),
]


@pytest.mark.parametrize("faults", [(), (VARIANT,)])
def test_runner_passes_both_readings(rig, faults):
    runner, _ = fuzz_runner(rig, faults)
    for example in RESERVED_EXAMPLES:
        assert runner.run(example) == [], example
    assert runner.final_check() == []


@pytest.mark.parametrize(("fault", "example", "words"), [
    ("double_abort", RESERVED_EXAMPLES[0], "2 replies"),  # the refusal twice
    ("abort_without_multiplexer", (fz.Request(frame(0x40, 0xF000, 3)),), "does not echo"),  # a valid initiate
])
def test_runner_still_fails_a_broken_rule_beside_the_variant(rig, fault, example, words):
    runner, _ = fuzz_runner(rig, (VARIANT, fault))
    problems = runner.run(example)
    assert any(words in p for p in problems), problems
