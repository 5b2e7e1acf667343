"""Documented manufacturer PDO behaviour: send-repeat counters and TPDO bits forced at init.

These tests apply only to profiles whose quirks declare the effect (e.g. SIKO WV58M/WH58M: 2800h
sends PDO1 n times per position change, 2801h limits the SYNC-driven PDO2, 1801h sub 1 bit 31 is
set again at every init). Each cites the quirk; every changed value is put back afterwards.
"""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import COB_ID_INVALID, can_id_of, cob_id_valid
from encoder_conformance.dut.link import Mark, format_frames, received_on
from encoder_conformance.dut.tpdo import TpdoUnderTest
from encoder_conformance.plugin.skips import not_applicable, not_equipped
from encoder_conformance.plugin.suite_helpers import documented_quirk
from encoder_conformance.profile import quirk_effects as fx

RESET_EVENTS = {"reset-node": "nmt_81h", "reset-communication": "nmt_82h"}


def _quirk_params(dut, effect: type[fx.P], evidence) -> fx.P:
    return documented_quirk(dut, effect, evidence, "the profile documents no such behaviour")


def _counter_spec(counters: dict[int, int], key: str) -> tuple[int, int]:
    """(comm index, counter object) of the quirk's ``tpdo1``/``tpdo2`` entry."""
    if not counters:
        not_applicable(f"the quirk names no {key} counter")
    return next(iter(counters.items()))


def _valid_cob_id(dut, comm: int, settings_journal) -> int:
    """The TPDO's 11-bit COB-ID, after clearing 18xxh sub 1 bit 31 (valid) if it was set."""
    cob_id = dut.read_uint(comm, 1)
    if cob_id & COB_ID_INVALID:
        settings_journal.write(comm, 1, cob_id_valid(cob_id).to_bytes(4, "little"))
    return can_id_of(cob_id)


def _window(dut) -> float:
    return dut.sdo_timeout + dut.profile.timing.nmt_settle_ms / 1000


@pytest.mark.spec("CiA 301 §7.2.2.2 (event-driven TPDO); manufacturer send-repeat counter (quirk)")
@pytest.mark.requires("tpdos")
def test_send_repeat_counter_sends_each_change_n_times(
    dut, settings_journal, back_to_preoperational, shaft, evidence
):
    """Counter 3, event timer 0: one position change gives exactly 3 frames, a still shaft none."""
    params = _quirk_params(dut, fx.PdoSendRepeatCounters, evidence)
    comm, counter = _counter_spec(params.per_change, "tpdo1")
    if shaft is None:
        not_equipped("needs a turning shaft: the simulator's shaft control (no bench drive configured)")
    repeats = min(3, params.counter_max)
    cob_id = _valid_cob_id(dut, comm, settings_journal)
    settings_journal.write(comm, 5, (0).to_bytes(2, "little"))
    settings_journal.write(counter, 0, bytes([repeats]))
    mark = dut.frames.mark()
    dut.nmt.transition("operational", settings_journal, evidence)
    turned = dut.frames.mark()
    shaft.turn_by(0.25)
    pdos = dut.pdos_counted(received_on(cob_id), repeats, turned, _window(dut))
    since_start = dut.frames.since(mark, received_on(cob_id))
    after_turn = {id(m) for m in dut.frames.since(turned)}
    standing = [m for m in since_start if id(m) not in after_turn]
    evidence.measure(f"TPDO {cob_id:03X}h frames for one position change", len(pdos), "frames", repeats, repeats)
    trace = format_frames(dut.frames.since(mark)[:30])
    assert not standing, f"{len(standing)} TPDO(s) on {cob_id:03X}h before the shaft moved:\n{trace}"
    assert len(pdos) == repeats, (
        f"{counter:04X}h = {repeats}, {comm:04X}h.05 = 0: expected {repeats} TPDOs on {cob_id:03X}h for one "
        f"position change (and none after), observed {len(pdos)} within {_window(dut) * 1000:.0f} ms\n{trace}"
    )


def _sync_burst(dut, cob_id: int, syncs: int, expected: int) -> tuple[list, Mark]:
    """Send ``syncs`` SYNCs; the TPDOs on ``cob_id`` (up to one more than ``expected``) and a mark."""
    mark = dut.frames.mark()
    for _ in range(syncs):
        dut.send_sync()
    return dut.pdos_counted(received_on(cob_id), expected, mark, _window(dut)), mark


@pytest.mark.spec("CiA 301 §7.2.2.2 (synchronous TPDO); manufacturer send-repeat counter (quirk)")
@pytest.mark.requires("tpdos")
def test_send_repeat_counter_limits_sync_tpdo(
    dut, settings_journal, back_to_preoperational, shaft, evidence
):
    """Type 1, counter 2: 6 SYNCs with a still shaft give 2 frames; after a position change 2 more."""
    params = _quirk_params(dut, fx.PdoSendRepeatCounters, evidence)
    comm, counter = _counter_spec(params.sync_limit, "tpdo2")
    limit = min(2, params.counter_max)
    cob_id = _valid_cob_id(dut, comm, settings_journal)
    TpdoUnderTest(dut, settings_journal, comm, 1).configure(trans_type=1)
    settings_journal.write(counter, 0, bytes([limit]))
    dut.nmt.transition("operational", settings_journal, evidence)
    for step in ("still shaft", "after a position change"):
        if step != "still shaft":
            if shaft is None:
                evidence.note("restart of the count after a position change not checked: no shaft drive")
                return
            shaft.turn_by(0.25)
        pdos, mark = _sync_burst(dut, cob_id, 6, limit)
        evidence.measure(f"TPDO {cob_id:03X}h frames for 6 SYNCs, {step}", len(pdos), "frames", limit, limit)
        assert len(pdos) == limit, (
            f"{comm:04X}h.02 = 1, {counter:04X}h = {limit}: expected {limit} TPDOs on {cob_id:03X}h for 6 SYNCs "
            f"({step}), observed {len(pdos)}\n{format_frames(dut.frames.since(mark)[:20])}"
        )


@pytest.mark.spec("CiA 301 §7.3.2.2.3 (reset: stored values reloaded); bits forced at init (quirk)")
@pytest.mark.parametrize("reset", sorted(RESET_EVENTS))
def test_bits_forced_again_at_init(dut, settings_journal, back_to_preoperational, reset, evidence):
    """The forced bits (SIKO: 1801h sub 1 bit 31, PDO2 disabled) are set again after NMT reset."""
    params = _quirk_params(dut, fx.BitsForcedAtInit, evidence)
    if RESET_EVENTS[reset] not in params.at:
        not_applicable(f"the quirk does not force the bits at {reset}")
    index, sub, bits = params.index, params.subindex, params.forced_bits
    label = f"{index:04X}h.{sub:02X}"
    size = len(dut.read(index, sub))
    settings_journal.write(index, sub, (dut.read_uint(index, sub) & ~bits).to_bytes(size, "little"))
    cleared = dut.read_uint(index, sub)
    assert not cleared & bits, f"{label} = {cleared:08X}h after writing it with {bits:08X}h cleared"
    mark = dut.nmt.command(reset)
    assert dut.wait_bootup(mark) is not None, f"no boot-up after {reset}"
    observed = dut.read_uint(index, sub)
    evidence.note(f"{label}: {cleared:08X}h written, {observed:08X}h after {reset}")
    assert observed & bits == bits, (
        f"{label} = {observed:08X}h after {reset}: bits {bits:08X}h must be set again at init "
        f"(written and stored as {cleared:08X}h)"
    )
