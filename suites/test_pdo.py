"""TPDO transmission: every n-th SYNC and the event timer (CiA 301 §7.2.2.2, §7.5.2.35).

Each test configures one TPDO through its communication parameter (put back afterwards),
starts the device and counts or times that TPDO's frames.
"""

from __future__ import annotations

import pytest

from encoder_conformance.checks import check_periodic, documented_quirk
from encoder_conformance.cia301 import COB_ID_INVALID, cob_id_valid
from encoder_conformance.dut.frames import format_frames
from encoder_conformance.dut.stimulus import pdo_stimulus
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("CiA 301 §7.2.2.2 (PDO transmission), §7.5.2.35"), pytest.mark.requires("tpdos")]


def _fixed_behaviour(dut, evidence) -> set[int]:
    """TPDOs whose behaviour a fixed-layout quirk decides (e.g. POSITAL 1800h: cyclic by 2200h, sub 2 ignored)."""
    found = dut.profile.quirk_of(fx.FixedTpdoMapping)
    if found is None:
        return set()
    quirk_id, params = found
    fixed = {spec.tpdo for spec in (*params.cyclic_tpdos, *params.polled_tpdos)}
    if fixed:
        title = dut.profile.quirks[quirk_id].title
        evidence.deviation(quirk_id, f"{title}: {', '.join(f'{c:04X}h' for c in sorted(fixed))} not used here")
    return fixed


def _configurable_tpdo(dut, sub: int, evidence, settings_journal, usable_types: list[int]) -> tuple[int, int]:
    """(comm index, transmission type to use) of the first TPDO that maps something, whose sub-index
    ``sub`` is writable and whose type is one of ``usable_types`` (in order of preference): to be
    written if sub 2 is writable, else as the device has it fixed. A disabled TPDO (sub 1 bit 31)
    is enabled for the test if sub 1 is writable.
    """
    fixed = _fixed_behaviour(dut, evidence)
    accepted = set(dut.profile.capabilities.tpdo_transmission_types)
    for comm in sorted(i for i in dut.profile.objects if 0x1800 <= i <= 0x19FF and i not in fixed):
        entry, kind, cob = (dut.profile.entry(comm, s) for s in (sub, 2, 1))
        if entry is None or kind is None or cob is None or not entry.writable:
            continue
        if dut.profile.entry(comm + 0x200, 0) is not None and dut.read_uint(comm + 0x200, 0) == 0:
            continue  # nothing mapped
        candidates = [t for t in usable_types if t in accepted] if kind.writable else [dut.read_uint(comm, 2)]
        chosen = next((t for t in candidates if t in usable_types), None)
        cob_id = dut.read_uint(comm, 1)
        if chosen is None or (cob_id & COB_ID_INVALID and not cob.writable):
            continue
        if cob_id & COB_ID_INVALID:
            settings_journal.write(comm, 1, cob_id_valid(cob_id).to_bytes(4, "little"))
            evidence.note(f"{comm:04X}h.01 bit 31 cleared (TPDO enabled) for the test")
        if not kind.writable:
            evidence.note(f"{comm:04X}h.02 is read-only: its fixed type {chosen} is used")
        return comm, chosen
    pytest.skip(f"not applicable: no mapped TPDO with writable sub-index {sub} and a usable transmission type")


def _start(dut):
    dut.nmt("start")


def test_sync_tpdo_sent_on_every_nth_sync(dut, settings_journal, back_to_preoperational, evidence):
    """Transmission type 3: the TPDO follows every third SYNC, so 9 SYNCs give exactly 3 frames."""
    comm, every = _configurable_tpdo(dut, 2, evidence, settings_journal, [3, *range(2, 241), 1])
    cob_id = dut.read_uint(comm, 1) & 0x7FF
    if dut.profile.entry(comm, 2).writable:
        settings_journal.write(comm, 2, bytes([every]))
    _start(dut)
    mark = dut.frames.mark()
    syncs = 3 * every
    for _ in range(syncs):
        dut.send_sync()
    window = dut.sdo_timeout + dut.profile.timing.nmt_settle_ms / 1000
    pdos = dut.pdos_counted(lambda m: m.is_rx and m.arbitration_id == cob_id, 3, mark, window)
    evidence.measure(f"TPDO {cob_id:03X}h frames for {syncs} SYNCs", len(pdos), "frames", 3, 3)
    assert len(pdos) == 3, (
        f"{comm:04X}h.02 = {every}: expected 3 TPDOs on {cob_id:03X}h for {syncs} SYNCs, observed {len(pdos)}\n"
        f"{format_frames(dut.frames.since(mark)[:20])}"
    )


def test_event_timer_period_within_tolerance(dut, settings_journal, back_to_preoperational, evidence):
    """Transmission type 255 with event timer T: the TPDO comes every T ms (>= 20 intervals, profile tolerance)."""
    comm, kind = _configurable_tpdo(dut, 5, evidence, settings_journal, [255, 254])
    cob_id = dut.read_uint(comm, 1) & 0x7FF
    timing = dut.profile.timing
    period = timing.heartbeat_test_period_ms
    if dut.profile.entry(comm, 2).writable:
        settings_journal.write(comm, 2, bytes([kind]))
    settings_journal.write(comm, 5, period.to_bytes(2, "little"))
    _start(dut)
    mark = dut.frames.mark()
    count = timing.heartbeat_intervals + 1
    frames = dut.frames.wait_count(
        lambda m: m.is_rx and m.arbitration_id == cob_id, count, count * period * 1.5 / 1000 + 0.5, mark
    )
    assert len(frames) == count, f"only {len(frames)} of {count} TPDOs on {cob_id:03X}h with event timer {period} ms"
    check_periodic([m.timestamp for m in frames], period, timing.heartbeat_tolerance, "event timer", evidence)


def test_type_255_without_event_timer_sends_nothing(dut, settings_journal, back_to_preoperational, shaft, evidence):
    """Documented quirk: transmission type 255 with event timer 0 switches the TPDO off (no SYNC, no change)."""
    documented_quirk(dut, fx.TransmissionType255Timer0Disables, evidence,
                     "CiA 301 type 255 without timer is event-driven")
    comm, _ = _configurable_tpdo(dut, 5, evidence, settings_journal, [255])
    cob_id = dut.read_uint(comm, 1) & 0x7FF
    if dut.profile.entry(comm, 2).writable:
        settings_journal.write(comm, 2, b"\xff")
    settings_journal.write(comm, 5, b"\x00\x00")
    _start(dut)
    control = shaft
    if control is None:
        evidence.note("hardware: only SYNCs are sent; turn the shaft during the test to cover position changes")
    mark = pdo_stimulus(dut, control)
    pdos = dut.frames.since(mark, lambda m: m.is_rx and m.arbitration_id == cob_id)
    evidence.measure(f"TPDO {cob_id:03X}h frames with type 255, timer 0", len(pdos), "frames", 0, 0)
    assert not pdos, (
        f"{comm:04X}h.02 = 255 and sub 5 = 0 must switch the TPDO off (documented); observed {len(pdos)} on "
        f"{cob_id:03X}h during 10 SYNCs{' and a turning shaft' if control else ''}:\n{format_frames(pdos[:5])}"
    )
