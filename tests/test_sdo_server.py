"""The simulator's SDO server protocol engine (CiA 301 §7.2.4), driven frame by frame.

A fake ObjectAccess stands in for the simulated node, so only the protocol is under test:
command specifiers, toggle bits, segment sizes, aborts and transfer state.
"""

from __future__ import annotations

import struct

import pytest

from encoder_conformance.sim.engine.sdo_server import SdoServer
from tests.sdo_server_rig import (
    COMMAND_INVALID,
    LENGTH_MISMATCH,
    NO_OBJECT,
    TEXT,
    TOGGLE,
    WRITE_RO,
    FakeAccess,
    abort_of,
    frame,
    segment,
)


@pytest.fixture
def access() -> FakeAccess:
    return FakeAccess()


@pytest.fixture
def server(access: FakeAccess) -> SdoServer:
    return SdoServer(access)


def test_expedited_upload_of_four_bytes(server):
    """Upload of a 4-byte value: scs 2, e=1, s=1, n=0 (43h) with index, sub and the data."""
    response = server.handle(frame(0x40, 0x1000, 0))
    assert response == bytes.fromhex("43 00 10 00 96 01 02 00")


def test_expedited_upload_of_one_byte_indicates_size(server):
    """Upload of a 1-byte value: n=3 unused bytes (4Fh)."""
    response = server.handle(frame(0x40, 0x1001, 0))
    assert response == bytes.fromhex("4F 01 10 00 00 00 00 00")


def test_expedited_download_with_size(server, access):
    """Download of 2 bytes (2Bh): confirmed with 60h + index/sub; exactly 2 bytes reach the object."""
    response = server.handle(frame(0x2B, 0x1017, 0, b"\xe8\x03"))
    assert response == bytes.fromhex("60 17 10 00 00 00 00 00")
    assert access.writes == [(0x1017, 0, b"\xe8\x03")]


def test_expedited_download_without_size_passes_four_bytes(server, access):
    """Download with e=1, s=0 (22h): the server takes all 4 data bytes."""
    server.handle(frame(0x22, 0x1017, 0, b"\x01\x02\x03\x04"))
    assert access.writes == [(0x1017, 0, b"\x01\x02\x03\x04")]


def test_expedited_abort_names_index_sub_and_code(server):
    """An access error on initiate answers 80h with the request's index/sub and the access's code."""
    assert abort_of(server.handle(frame(0x40, 0x1234, 5))) == (0x1234, 5, NO_OBJECT)
    assert abort_of(server.handle(frame(0x23, 0x1000, 0, b"\x00" * 4))) == (0x1000, 0, WRITE_RO)


def test_segmented_upload_of_a_20_byte_string(server):
    """Initiate announces 20 bytes (41h); segments carry 7+7+6 bytes, toggles 0/1/0, last has c=1, n=1."""
    initiate = server.handle(frame(0x40, 0x1008, 0))
    assert initiate == bytes.fromhex("41 08 10 00 14 00 00 00")
    first = server.handle(segment(0x60))
    second = server.handle(segment(0x70))
    third = server.handle(segment(0x60))
    assert first == b"\x00" + TEXT[0:7]
    assert second == b"\x10" + TEXT[7:14]
    assert third == b"\x03" + TEXT[14:20] + b"\x00"
    assert first[1:] + second[1:] + third[1:7] == TEXT
    # the transfer is over: another segment request is a protocol error
    assert abort_of(server.handle(segment(0x70)))[2] == COMMAND_INVALID


def test_segmented_upload_ending_on_a_full_segment(server, access):
    """14 bytes: two full segments, the second with c=1 and n=0 (11h)."""
    access.values[(0x1008, 0)] = TEXT[:14]
    assert server.handle(frame(0x40, 0x1008, 0)) == bytes.fromhex("41 08 10 00 0E 00 00 00")
    assert server.handle(segment(0x60)) == b"\x00" + TEXT[:7]
    assert server.handle(segment(0x70)) == b"\x11" + TEXT[7:14]


def test_segmented_download(server, access):
    """Initiate with size 10 (21h), segments 00h (7 bytes) and 19h (3 bytes, n=4, c=1): one write of 10 bytes."""
    data = b"0123456789"
    assert server.handle(frame(0x21, 0x2000, 0, struct.pack("<I", 10))) == bytes.fromhex("60 00 20 00 00 00 00 00")
    assert server.handle(segment(0x00, data[:7])) == bytes.fromhex("20 00 00 00 00 00 00 00")
    assert access.writes == [], "the value must be written only after the last segment"
    assert server.handle(segment(0x19, data[7:])) == bytes.fromhex("30 00 00 00 00 00 00 00")
    assert access.writes == [(0x2000, 0, data)]


def test_wrong_toggle_in_upload_aborts_05030000(server):
    """A segment request repeating the previous toggle aborts 05030000h for the transfer's index/sub."""
    server.handle(frame(0x40, 0x1008, 0))
    server.handle(segment(0x60))
    assert abort_of(server.handle(segment(0x60))) == (0x1008, 0, TOGGLE)
    # the transfer is gone after the abort
    assert abort_of(server.handle(segment(0x70)))[2] == COMMAND_INVALID


def test_wrong_toggle_in_download_aborts_05030000(server, access):
    """First download segment with t=1 aborts 05030000h for the transfer's index/sub; nothing is written."""
    server.handle(frame(0x21, 0x2000, 0, struct.pack("<I", 10)))
    assert abort_of(server.handle(segment(0x10, b"0123456"))) == (0x2000, 0, TOGGLE)
    assert access.writes == []


@pytest.mark.parametrize("command", [0xA0, 0xC0, 0xE0], ids=["ccs5-block-upload", "ccs6-block-download", "ccs7"])
def test_unknown_command_specifier_aborts_05040001(server, command):
    """Block transfer and reserved command specifiers are answered with abort 05040001h."""
    assert abort_of(server.handle(frame(command, 0x1008, 0))) == (0x1008, 0, COMMAND_INVALID)


def test_segment_without_transfer_aborts_05040001(server):
    """Upload/download segment requests without an initiate are protocol errors."""
    assert abort_of(server.handle(segment(0x60)))[2] == COMMAND_INVALID
    assert abort_of(server.handle(segment(0x00, b"x")))[2] == COMMAND_INVALID


def test_client_abort_clears_the_transfer(server):
    """An abort from the client (80h) is not answered and ends the segmented transfer."""
    server.handle(frame(0x40, 0x1008, 0))
    assert server.handle(frame(0x80, 0x1008, 0, struct.pack("<I", 0x08000000))) is None
    assert abort_of(server.handle(segment(0x60)))[2] == COMMAND_INVALID


def test_new_initiate_replaces_a_transfer_in_progress(server):
    """A new initiate during a segmented upload starts over (the old transfer is dropped)."""
    server.handle(frame(0x40, 0x1008, 0))
    server.handle(segment(0x60))
    assert server.handle(frame(0x40, 0x1001, 0)) == bytes.fromhex("4F 01 10 00 00 00 00 00")
    assert abort_of(server.handle(segment(0x70)))[2] == COMMAND_INVALID


@pytest.mark.parametrize("length", [0, 1, 4, 7, 9])
def test_frames_not_8_bytes_get_no_response(server, access, length):
    """CiA 301: SDO frames have DLC 8; shorter or longer frames are ignored (no response, no write)."""
    request = frame(0x2F, 0x1017, 0, b"\x01")[:length].ljust(length, b"\x00")
    assert server.handle(request) is None
    assert access.writes == []


def test_short_frame_does_not_disturb_a_transfer(server):
    """A DLC<8 frame in the middle of a segmented upload is ignored; the transfer continues."""
    server.handle(frame(0x40, 0x1008, 0))
    assert server.handle(b"\x60") is None
    assert server.handle(segment(0x60)) == b"\x00" + TEXT[0:7]


def test_reset_drops_the_transfer(server):
    """reset() (NMT reset, power cycle) forgets a transfer in progress."""
    server.handle(frame(0x40, 0x1008, 0))
    server.reset()
    assert abort_of(server.handle(segment(0x60)))[2] == COMMAND_INVALID


def test_abort_at_last_download_segment_names_the_transfer(server):
    """A write refused after the last segment aborts with the transfer's index/sub (CiA 301 §7.2.4.3.17)."""
    server.handle(frame(0x21, 0x1008, 0, struct.pack("<I", 10)))
    server.handle(segment(0x00, b"ABCDEFG"))
    assert abort_of(server.handle(segment(0x19, b"HIJ"))) == (0x1008, 0, WRITE_RO)


def test_download_size_mismatch_aborts_06070010_for_the_transfer(server, access):
    """Segments totalling a different size than the initiate announced abort 06070010h; nothing is written."""
    server.handle(frame(0x21, 0x2000, 0, struct.pack("<I", 12)))
    server.handle(segment(0x00, b"ABCDEFG"))
    assert abort_of(server.handle(segment(0x19, b"HIJ"))) == (0x2000, 0, LENGTH_MISMATCH)
    assert access.writes == []


def test_upload_of_an_empty_value(server):
    """An empty value (e.g. a VISIBLE_STRING "") uploads as 0 bytes: segmented with size 0 or e=1, s=0."""
    response = server.handle(frame(0x40, 0x1009, 0))
    assert response is not None
    assert response[0] & 0x10 == 0, f"reserved bit 4 set in {response.hex(' ')}"
    assert response[0] in (0x41, 0x42), f"no CiA 301 encoding of 0 bytes: {response.hex(' ')}"
    if response[0] == 0x41:
        assert struct.unpack_from("<I", response, 4)[0] == 0
