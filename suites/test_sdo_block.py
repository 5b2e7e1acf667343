"""SDO block transfer (CiA 301 §7.2.4.3.9-16): served where the profile declares it, refused where not.

CTT cases SDO 19-27: block upload and download with and without CRC, a wrong block size, a wrong
sequence number. Where the profile declares no block transfer (``capabilities.block_sdo: false``)
a block initiate must be refused with 05040001h (command specifier not valid); a device whose
manual mentions block transfer without protocol detail (quirk effect ``block_transfer_unconfirmed``,
e.g. WDGA M §8.3.2) may also serve it: either is recorded, neither fails. Written: a harmless
16-bit entry (1017h where declared), put back. Each test that opens a transfer closes it: where it
did not end (a failure, a refusal), the ``closing`` fixture aborts it and watches the SDO silence
window before the put-back, so that no read lands inside a sub-block the device still waits for.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator

import pytest

from encoder_conformance.cia.cia301 import SdoAbortCode, block_crc
from encoder_conformance.dut.sdo import SdoProtocolClient
from encoder_conformance.plugin.skips import not_applicable
from encoder_conformance.plugin.suite_helpers import judge_refusal
from encoder_conformance.profile import datatypes
from encoder_conformance.profile import quirk_effects as fx

pytestmark = pytest.mark.spec("CiA 301 §7.2.4.3.9-16 (SDO block transfer)")

#: entries harmless to write (and put back): heartbeat and guard times, the position's cyclic timer
HARMLESS_16_BIT = [(0x1017, 0), (0x100C, 0), (0x6200, 0)]
BLOCK = "CiA 301 §7.2.4.3.9-16 (SDO block download / upload)"


@pytest.fixture
def sdo(dut) -> SdoProtocolClient:
    return dut.sdo.protocol()


class OpenTransfers:
    """The transfers a test opened; those not ``ended`` are aborted by the client at teardown."""

    def __init__(self) -> None:
        self.open: list[tuple[int, int]] = []

    def opened(self, key: tuple[int, int]) -> tuple[int, int]:
        self.open.append(key)
        return key

    def ended(self, key: tuple[int, int]) -> None:
        self.open = [k for k in self.open if k != key]


@pytest.fixture
def closing(dut, sdo, settings_journal, evidence) -> Iterator[OpenTransfers]:
    """Aborts (CiA 301 §7.2.4.3.17) every transfer the test left open, then watches the SDO silence window (an
    abort is not answered), before ``settings_journal`` puts values back."""
    transfers = OpenTransfers()
    yield transfers
    if not dut.usable:
        return
    for index, sub in transfers.open:
        late = sdo.silent_after(sdo.abort(index, sub, SdoAbortCode.GENERAL_ERROR))
        evidence.note(f"{index:04X}h.{sub:02X}: transfer left open by the test, aborted by the client"
                      + (f"; the device then sent {[f.hex(' ').upper() for f in late]}" if late else ""))


def _target(dut) -> tuple[int, int]:
    for key in HARMLESS_16_BIT:
        entry = dut.profile.entry(*key)
        if entry is not None and entry.writable and entry.readable and datatypes.size_bytes(entry.type) == 2:
            return key
    not_applicable("the profile declares no harmless writable 16-bit entry (1017h, 100Ch, 6200h)")


def _other_value(current: bytes) -> bytes:
    return (1234 if int.from_bytes(current, "little") != 1234 else 1235).to_bytes(2, "little")


def _longest_static(dut) -> tuple[int, int]:
    """The longest readable entry whose value does not move by itself (so block and segmented reads agree)."""
    entries = [(datatypes.size_bytes(e.type) or 0, i, s) for i, s, _, e in dut.profile.iter_entries()
               if e.readable and not e.dynamic]
    _, index, sub = max(entries)
    return index, sub


@pytest.mark.requires("block_sdo")
@pytest.mark.parametrize("crc", [True, False], ids=["crc", "no-crc"])
def test_block_upload(dut, sdo, crc, closing, evidence):
    """Block upload of the longest static entry (blksize 1: a sub-block per segment): the initiate response echoes
    it, sequence numbers count from 1, the size and (with CRC) the CRC match, the data is what a plain read gives."""
    evidence.rests_on("cia", BLOCK)
    key = _longest_static(dut)
    result = sdo.block_upload(*closing.opened(key), blksize=1, crc=crc)
    if result.ok or result.abort is not None:
        closing.ended(key)
    assert result.ok, f"block upload of {key[0]:04X}h.{key[1]:02X}:\n{result.describe()}"
    plain = sdo.upload(*key)
    assert result.data == plain.data, f"block upload {result.data.hex(' ')}, plain upload {plain.data.hex(' ')}"


@pytest.mark.requires("block_sdo")
@pytest.mark.parametrize("crc", [True, False], ids=["crc", "no-crc"])
def test_block_download(dut, sdo, crc, settings_journal, closing, evidence):
    """Block download to a 16-bit entry: initiate, one segment, block acknowledgement, end (with or without CRC)
    confirmed, and the value read back."""
    evidence.rests_on("cia", BLOCK)
    key = _target(dut)
    current = dut.read(*key)
    value = _other_value(current)
    settings_journal.remember(*key, current)
    result = sdo.block_download(*closing.opened(key), value, crc=crc)
    if result.ok or result.abort is not None:
        closing.ended(key)
    assert result.ok, f"block download of {value.hex(' ')} to {key[0]:04X}h.{key[1]:02X}:\n{result.describe()}"
    assert dut.read(*key) == value


@pytest.mark.requires("block_sdo")
def test_block_download_wrong_crc_refused(dut, sdo, settings_journal, closing, evidence):
    """A block download whose end carries a wrong CRC is refused with 05040004h; nothing is written."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.12 (end SDO block download: CRC), §7.2.4.3.17 05040004h")
    key = _target(dut)
    current = dut.read(*key)
    value = _other_value(current)
    settings_journal.remember(*key, current)
    result = sdo.block_download(*closing.opened(key), value, crc_value=block_crc(value) ^ 0x5A5A)
    if result.abort is not None:
        closing.ended(key)
    assert result.abort is not None, f"block download with a wrong CRC, no abort:\n{result.describe()}"
    judge_refusal(dut, result.abort, {SdoAbortCode.CRC_ERROR}, {SdoAbortCode.GENERAL_ERROR},
                  "block download with a wrong CRC", evidence)
    assert dut.read(*key) == current, f"{key[0]:04X}h.{key[1]:02X} changed by a block download with a wrong CRC"


@pytest.mark.requires("block_sdo")
@pytest.mark.parametrize("blksize", [0, 128])
def test_block_upload_invalid_block_size_refused(dut, sdo, blksize, evidence):
    """Block upload with blksize 0 or 128 (CiA 301: 1..127) is refused with 05040002h (CTT SDO 26)."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.14 (blksize 0 < blksize < 128), §7.2.4.3.17 05040002h")
    key = (0x1000, 0)
    response = sdo.block_upload_initiate(*key, blksize)
    if response is not None and not response.is_abort:
        sdo.abort(*key, SdoAbortCode.BLOCK_SIZE)
    tolerated = {SdoAbortCode.COMMAND_SPECIFIER, SdoAbortCode.GENERAL_ERROR}
    judge_refusal(dut, response, {SdoAbortCode.BLOCK_SIZE}, tolerated, f"block upload with block size {blksize}",
                  evidence)


@pytest.mark.requires("block_sdo")
def test_block_download_wrong_sequence_number(dut, sdo, settings_journal, closing, evidence):
    """A first segment numbered 2 is not taken: the acknowledgement says no segment arrived in order (ackseq 0, at
    once or after the device's sub-block time-out; the client repeats) or the transfer aborts 05040003h (CTT SDO 27,
    or 05040000h after the time-out; the CTT also accepts 05040001h and 08000000h there); repeated in order, the
    value is written."""
    evidence.rests_on("cia", "CiA 301 v4.2.0 §7.2.4.3 (SDO block download: ackseq names the last segment received in "
                              "order), §7.2.4.3.17 (abort)")
    key = _target(dut)
    current = dut.read(*key)
    value = _other_value(current)
    settings_journal.remember(*key, current)
    started = sdo.block_download_initiate(*closing.opened(key), 2)
    assert started is not None, "no response to initiate block download"
    assert started.raw[0] & 0xE3 == 0xA0, f"initiate block download refused: {started.describe()}"
    # the device may wait for the rest of the sub-block until its time-out (open reading sdo-block-subblock-timeout)
    timeout_ms = dut.profile.timing.sdo_transfer_timeout_ms
    mark = sdo.send_block_segment(2, value, last=True)
    ack = sdo.wait_response(mark, timeout=timeout_ms / 1000 + dut.sdo_timeout)
    if ack is not None:
        evidence.measure("segment out of sequence to the server's answer", round(_delay_s(dut, mark, ack) * 1000, 1),
                         "ms", high=timeout_ms + dut.sdo_timeout * 1000)
    if ack is not None and ack.is_abort:
        closing.ended(key)
        judge_refusal(dut, ack, {SdoAbortCode.SEQUENCE_NUMBER, SdoAbortCode.TIMEOUT},
                      {SdoAbortCode.COMMAND_SPECIFIER, SdoAbortCode.GENERAL_ERROR},
                      "block segment with sequence number 2 first", evidence)
        assert dut.read(*key) == current, "the aborted block download changed the value"
        return
    assert ack is not None, (f"no block acknowledgement (nor abort) within the device's sub-block time-out "
                             f"(timing.sdo_transfer_timeout_ms = {timeout_ms:g} ms) and the answer window after a "
                             "segment out of sequence")
    assert ack.raw[0] & 0xE3 == 0xA2, f"not a block acknowledgement: {ack.describe()}"
    assert ack.raw[1] == 0, f"ackseq {ack.raw[1]} acknowledges a segment that came out of sequence (2 before 1)"
    ack = sdo.wait_response(sdo.send_block_segment(1, value, last=True))
    assert ack is not None, "no block acknowledgement after the repeated segment"
    assert ack.raw[:2] == b"\xa2\x01", f"the repeated segment 1 is not acknowledged: {ack.describe()}"
    crc = block_crc(value) if started.raw[0] & 0x04 else 0  # both sides support CRC: the data's
    end = sdo.wait_response(dut.send_sdo(struct.pack("<BH5x", 0xC1 | 5 << 2, crc)))  # n = 5 unused bytes
    assert end is not None, "no response to end block download"
    if end.raw[0] & 0xE3 == 0xA1 or end.is_abort:
        closing.ended(key)
    assert end.raw[0] & 0xE3 == 0xA1, f"end block download after the repeated segment: {end.describe()}"
    assert dut.read(*key) == value, "the repeated block download was confirmed but the value is not written"


def _delay_s(dut, mark, response) -> float:
    """Seconds from the frame after ``mark`` (the segment sent) to ``response``."""
    frames = dut.frames.since(mark)
    sent = next((m.timestamp for m in frames if not m.is_rx), None)
    got = next((m.timestamp for m in frames if m.is_rx and bytes(m.data) == response.raw), None)
    return 0.0 if sent is None or got is None else got - sent


def test_block_initiate_refused_without_block_transfer(dut, sdo, evidence):
    """Where the profile declares no block transfer, block upload and download initiates are refused with
    05040001h (CTT SDO 19/22) echoing the entry; a device whose manual leaves block transfer unconfirmed may
    serve them instead (recorded)."""
    if dut.profile.capabilities.block_sdo:
        not_applicable("the profile declares block transfer (test_block_upload and others check it)")
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.17 05040001h (client/server command specifier not valid or unknown)")
    unconfirmed = dut.profile.quirk(fx.BlockTransferUnconfirmed)
    if unconfirmed is not None:
        evidence.deviation(unconfirmed.id, unconfirmed.quirk.title)
    key = (0x1000, 0)
    initiates = {"block upload": lambda: sdo.block_upload_initiate(*key, 127),
                 "block download": lambda: sdo.block_download_initiate(*key, 4)}
    for what, initiate in initiates.items():
        mark = dut.frames.mark()
        response = initiate()
        others = [bytes(m.data).hex(" ").upper() for m in dut.frames.since(mark, sdo.is_response)]
        assert response is not None or not others, f"{what} initiate answered with {others} (neither a block " \
                                                   "response nor an abort for 1000h.00)"
        if response is not None and not response.is_abort:
            sdo.abort(*key, SdoAbortCode.GENERAL_ERROR)
            if unconfirmed is not None:
                evidence.note(f"{what} initiate served ({response.describe()}): block transfer works although the "
                              f"profile declares block_sdo false (quirk {unconfirmed.id})")
                continue
        judge_refusal(dut, response, {SdoAbortCode.COMMAND_SPECIFIER}, set(), f"{what} initiate", evidence)
        assert response is not None
        named = response.raw[1:4]
        assert named == struct.pack("<HB", *key), f"{what}: the abort {response.describe()} does not echo 1000h.00"
