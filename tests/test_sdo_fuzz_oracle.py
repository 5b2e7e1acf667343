"""The SDO fuzzer's judge, reply attribution, exclusion list, strategies and replay (encoder_conformance.fuzz)."""

from __future__ import annotations

import struct

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from encoder_conformance.fuzz import exclusions, replay
from encoder_conformance.fuzz import strategies as fz
from encoder_conformance.fuzz.attribution import attribute
from encoder_conformance.fuzz.oracle import Exchange, Judge
from encoder_conformance.plugin import hypothesis_profiles
from encoder_conformance.profile.loader import load_profile

UPLOAD_1000 = bytes.fromhex("40 00 10 00 00 00 00 00")
ANSWER_1000 = bytes.fromhex("43 00 10 00 96 01 02 00")
ABORT_NO_OBJECT = bytes.fromhex("80 00 00 00 00 00 02 06")
CLIENT_ABORT = bytes.fromhex("80 08 10 00 00 00 04 05")
UPLOAD_1008 = bytes.fromhex("40 08 10 00 00 00 00 00")
SEGMENTED_1008 = bytes.fromhex("41 08 10 00 0A 00 00 00")


def _judge(*pairs: tuple[bytes, list[bytes]], refused: bool = False) -> list[str]:
    return Judge().judge([Exchange(fz.Request(frame, refused), replies) for frame, replies in pairs])


@pytest.fixture(scope="module")
def wdga():
    return load_profile("wachendorff-wdga-mt").profile


# -- the judge ---------------------------------------------------------------------------
def test_one_fitting_reply_passes():
    assert _judge((UPLOAD_1000, [ANSWER_1000])) == []


@pytest.mark.parametrize(("replies", "words"), [
    ([], "no reply"),
    ([ANSWER_1000, ANSWER_1000], "2 replies"),
    ([ANSWER_1000[:6]], "DLC 6"),
    ([bytes.fromhex("60 00 10 00 00 00 00 00")], "does not answer client command 2"),
    ([bytes.fromhex("43 01 10 00 00 00 00 00")], "does not echo"),
    ([bytes.fromhex("80 01 10 00 00 00 02 06")], "does not echo"),
    ([bytes.fromhex("81 00 10 00 00 00 02 06")], "command byte of an abort is 80h"),
])
def test_upload_initiate_problems(replies, words):
    problems = _judge((UPLOAD_1000, replies))
    assert problems
    assert words in problems[0]


def test_client_abort_must_not_be_answered():
    assert _judge((CLIENT_ABORT, [])) == []
    assert "abort transfer request" in _judge((CLIENT_ABORT, [CLIENT_ABORT]))[0]


def test_short_frame_ignored_aborted_or_served_once():
    """Open reading sdo-short-frame: ignored, one abort naming any multiplexer, or served where its bytes carry the
    request (a 5-byte upload of 1000h answered as one); never answered twice, nor served without the request's
    bytes, nor with another multiplexer."""
    assert _judge((UPLOAD_1000[:5], [])) == []
    assert _judge((UPLOAD_1000[:5], [ABORT_NO_OBJECT])) == []
    assert _judge((UPLOAD_1000[:5], [ANSWER_1000])) == []
    assert _judge((UPLOAD_1000[:4], [ANSWER_1000])) == []
    assert "do not carry the request" in _judge((UPLOAD_1000[:3], [ANSWER_1000]))[0]
    wrong_mux = _judge((UPLOAD_1000[:5], [bytes.fromhex("43 08 10 00 01 00 00 00")]))
    assert "served as upload 1000h.00" in wrong_mux[0]
    assert "does not echo" in wrong_mux[0]
    assert "2 replies" in _judge((b"", [ABORT_NO_OBJECT, ABORT_NO_OBJECT]))[0]
    assert "2 replies" in _judge((UPLOAD_1000[:5], [ANSWER_1000, ANSWER_1000]))[0]


def test_a_short_download_initiate_is_served_only_with_its_multiplexer():
    """6 bytes of an expedited download of 2 bytes carry it (served as a refused write: the abort, never a
    confirmation); 3 bytes lack its sub-index."""
    write = bytes.fromhex("2B 00 10 00 01 02 00 00")
    confirmed, refused = bytes.fromhex("60 00 10 00 00 00 00 00"), bytes.fromhex("80 00 10 00 02 00 01 06")
    assert _judge((write[:6], [refused]), refused=True) == []
    assert "must be refused" in _judge((write[:6], [confirmed]), refused=True)[0]
    assert "do not carry the request" in _judge((write[:3], [confirmed]), refused=True)[0]


def test_a_failure_names_the_request_and_both_answers():
    """A last segment confirmed and then aborted: two answers to one request, both named, with the time between."""
    from encoder_conformance.dut.sdo.sdo_words import Stamped

    initiate = bytes.fromhex("21 00 20 00 0C 00 00 00")
    last = bytes.fromhex("15 01 02 03 04 05 00 00")
    confirm, abort = Stamped(bytes.fromhex("30 00 00 00 00 00 00 00"), 1.0), Stamped(
        bytes.fromhex("80 00 20 00 10 00 07 06"), 1.000013)
    problems = _judge((initiate, [bytes.fromhex("60 00 20 00 00 00 00 00")]),
                      (bytes.fromhex("00 01 02 03 04 05 06 07"), [bytes.fromhex("20 00 00 00 00 00 00 00")]),
                      (last, [confirm, abort]))
    assert len(problems) == 1, problems
    text = problems[0]
    assert text.startswith("download segment, toggle 1, 5 bytes, the last (15 01"), text
    assert "2 replies to one request: confirmed (30 00" in text
    assert "then 0.013 ms later abort 06070010h" in text
    assert "naming 2000h.00" in text


def test_refused_write_confirmed():
    request = bytes.fromhex("2F 00 10 00 01 00 00 00")
    assert "must be refused" in _judge((request, [bytes.fromhex("60 00 10 00 00 00 00 00")]), refused=True)[0]
    assert _judge((request, [bytes.fromhex("80 00 10 00 02 00 01 06")]), refused=True) == []


def test_segmented_upload_in_order_passes():
    assert _judge(
        (UPLOAD_1008, [SEGMENTED_1008]),
        (bytes.fromhex("60 00 00 00 00 00 00 00"), [bytes.fromhex("00 57 44 47 41 2D 4D 54")]),
        (bytes.fromhex("70 00 00 00 00 00 00 00"), [bytes.fromhex("1B 2D 43 4F 00 00 00 00")]),
    ) == []


def test_segment_with_toggle_out_of_order_must_be_aborted():
    toggle_1 = bytes.fromhex("70 00 00 00 00 00 00 00")
    assert "toggle 1 (expected 0)" in _judge((UPLOAD_1008, [SEGMENTED_1008]),
                                              (toggle_1, [bytes.fromhex("10 57 44 47 41 2D 4D 54")]))[0]
    assert _judge((UPLOAD_1008, [SEGMENTED_1008]), (toggle_1, [bytes.fromhex("80 08 10 00 00 00 03 05")])) == []


def test_abort_during_a_transfer_carries_its_multiplexer():
    segment = bytes.fromhex("70 00 00 00 00 00 00 00")
    problems = _judge((UPLOAD_1008, [SEGMENTED_1008]), (segment, [bytes.fromhex("80 00 00 00 00 00 03 05")]))
    assert "does not carry its multiplexer" in problems[0]


def test_segment_without_transfer_must_be_aborted():
    assert "no transfer is open" in _judge((bytes.fromhex("60 00 00 00 00 00 00 00"),
                                            [bytes.fromhex("00 00 00 00 00 00 00 00")]))[0]
    assert _judge((bytes.fromhex("60 00 00 00 00 00 00 00"), [bytes.fromhex("80 00 00 00 01 00 04 05")])) == []


def test_after_an_aborted_initiate_during_a_transfer_segments_are_not_judged():
    """The device may go on with the transfer it had open: its segment response is no fault."""
    assert _judge(
        (UPLOAD_1008, [SEGMENTED_1008]),
        (UPLOAD_1000, [bytes.fromhex("80 00 10 00 01 00 04 05")]),
        (bytes.fromhex("60 00 00 00 00 00 00 00"), [bytes.fromhex("00 57 44 47 41 2D 4D 54")]),
    ) == []


# -- attribution -------------------------------------------------------------------------
def _requests(*frames: bytes) -> list[fz.Request]:
    return [fz.Request(f) for f in frames]


def test_a_second_reply_counts_against_its_request():
    exchanges, stray = attribute(_requests(UPLOAD_1000, UPLOAD_1008),
                                 [(True, UPLOAD_1000), (False, ANSWER_1000), (True, UPLOAD_1008),
                                  (False, ANSWER_1000), (False, SEGMENTED_1008)])
    assert [len(e.replies) for e in exchanges] == [2, 1]
    assert stray == []


def test_the_reply_to_a_short_frame_is_not_taken_for_the_next_requests():
    short = bytes.fromhex("40 08 10")
    exchanges, _ = attribute(_requests(short, UPLOAD_1000),
                             [(True, short), (True, UPLOAD_1000), (False, ABORT_NO_OBJECT), (False, ANSWER_1000)])
    assert [e.replies for e in exchanges] == [[ABORT_NO_OBJECT], [ANSWER_1000]]


def test_consecutive_segments_each_get_their_reply():
    first, second = bytes.fromhex("60 00 00 00 00 00 00 00"), bytes.fromhex("70 00 00 00 00 00 00 00")
    one, two = bytes.fromhex("00 57 44 47 41 2D 4D 54"), bytes.fromhex("1B 2D 43 4F 00 00 00 00")
    exchanges, _ = attribute(_requests(first, second), [(True, first), (False, one), (True, second), (False, two)])
    assert [e.replies for e in exchanges] == [[one], [two]]


def test_replies_before_the_first_request_are_stray():
    exchanges, stray = attribute(_requests(UPLOAD_1000), [(False, ABORT_NO_OBJECT), (True, UPLOAD_1000),
                                                           (False, ANSWER_1000)])
    assert stray == [ABORT_NO_OBJECT]
    assert exchanges[0].replies == [ANSWER_1000]


# -- what may be sent --------------------------------------------------------------------
@pytest.mark.parametrize(("profile", "indices"), [
    ("wachendorff-wdga-mt", {0x1010, 0x1011, 0x2100, 0x2101, 0x6003}),
    ("waycon-sx", {0x1010, 0x1011, 0x2101, 0x2105}),
    ("faulhaber-mc5005", {0x1010, 0x1011, 0x2400}),
    ("fraba-posital-awc58-c2-mt", {0x1010, 0x1011, 0x2300}),
    ("siko-wx58m-1212-mt", {0x1010, 0x1011, 0x2002}),
])
def test_exclusions_derived_from_the_profile(profile, indices):
    excluded = exclusions.never_write(load_profile(profile).profile)
    assert indices <= set(excluded)
    assert all(excluded.values())  # a reason for each


def test_a_profile_adds_exclusions_with_a_reason(wdga):
    extended = wdga.model_copy(update={"sdo_fuzz_never_write": {0x2120: "customer data: the owner's notes"}})
    assert "customer data" in exclusions.never_write(extended)[0x2120]


def _every_frame(targets: fz.Targets) -> st.SearchStrategy[fz.Example]:
    single = st.one_of(fz.initiates(targets), fz.reserved_commands(targets), fz.truncated(fz.initiates(targets)))
    return st.one_of(st.tuples(single), fz.segment_sequences(targets), fz.interleaved_transfers(targets))


@pytest.mark.parametrize("profile", ["wachendorff-wdga-mt", "waycon-sx", "faulhaber-mc5005"])
def test_no_generated_frame_writes_what_it_must_not(profile):
    loaded = load_profile(profile).profile
    excluded, auto = exclusions.never_write(loaded), exclusions.self_storing(loaded)
    targets = fz.Targets.of(loaded, excluded, auto)
    writable = set(targets.writable)

    @settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(_every_frame(targets))
    def check(example):
        opened: tuple[int, int] | None = None
        for request in example:
            frame = request.frame
            assert targets.may_download(frame), str(request)
            if len(frame) >= 4 and frame[0] >> 5 == 1:
                mux = struct.unpack_from("<HB", frame, 1)
                assert not frame[0] & 0x02 or mux not in writable, f"expedited write to {mux}: {request}"
                opened = mux if len(frame) == 8 else opened
            if len(frame) >= 1 and frame[0] >> 5 == 0 and opened in writable:
                assert not frame[0] & 0x01, f"last segment to writable {opened}: {request}"

    check()


# -- the report ----------------------------------------------------------------------------
def test_replay_lines():
    requests = _requests(UPLOAD_1000[:3], UPLOAD_1000)
    lines = replay.candump_lines(0x605, requests).splitlines()
    assert lines == ["(0.000000) can0 605#400010", "(0.010000) can0 605#4000100000000000"]
    snippet = replay.python_snippet(0x605, requests)
    assert "arbitration_id=0x605" in snippet
    assert '"40 00 10"' in snippet
    compile(snippet, "replay", "exec")


def test_hypothesis_profiles_registered():
    hypothesis_profiles.register()
    assert settings.get_profile("ci").derandomize
    assert settings.get_profile("soak").max_examples > settings.get_profile("bench").max_examples


def test_a_short_frames_answer_that_looks_like_the_next_requests_is_given_back():
    """The short frame's echo arrives after the next request went out and fits it: the device answers in
    order, so the first of the two replies belongs to the short frame."""
    short = UPLOAD_1000[:3]
    echo = UPLOAD_1000
    exchanges, _ = attribute(_requests(short, UPLOAD_1000),
                             [(True, short), (True, UPLOAD_1000), (False, echo), (False, ANSWER_1000)])
    assert [e.replies for e in exchanges] == [[echo], [ANSWER_1000]]


def test_a_late_abort_to_a_short_frame_is_its_own_not_the_closing_aborts():
    """Seen in a bench run against the twin that aborts short frames: its abort, naming 1000h.00, came 1.8 ms after
    a 6-byte frame, after the closing abort and the read of 1000h went out; it is the short frame's (a client's abort
    draws none), and the read keeps its own answer."""
    short, closing = bytes.fromhex("2C 61 DF FB 60 AF"), bytes.fromhex("80 61 DF FB 00 00 04 05")
    abort = bytes.fromhex("80 00 10 00 01 00 04 05")
    events = [(True, short), (True, closing), (True, UPLOAD_1000), (False, abort), (False, ANSWER_1000)]
    exchanges, stray = attribute(_requests(short, closing, UPLOAD_1000), events)
    assert [e.replies for e in exchanges] == [[abort], [], [ANSWER_1000]]
    assert stray == []
    assert Judge().judge(exchanges) == []
