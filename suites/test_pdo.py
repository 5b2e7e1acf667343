"""TPDO transmission: every n-th SYNC and the event timer (CiA 301 §7.2.2.2, §7.5.2.35).

Each test configures one TPDO through its communication parameter (put back afterwards),
starts the device and counts or times that TPDO's frames.
"""

from __future__ import annotations

import allure
import pytest

from encoder_conformance.checks import documented_quirk
from encoder_conformance.dut.frames import format_frames
from encoder_conformance.dut.stimulus import pdo_stimulus
from encoder_conformance.timing import interval_stats

pytestmark = [pytest.mark.spec("CiA 301 §7.2.2.2 (PDO transmission), §7.5.2.35"), pytest.mark.requires("tpdos")]


def _fixed_behaviour(dut, evidence) -> set[int]:
    """TPDOs whose behaviour a fixed-layout quirk decides (e.g. POSITAL 1800h: cyclic by 2200h, sub 2 ignored)."""
    found = dut.profile.quirk_with_effect("fixed_tpdo_mapping")
    if found is None:
        return set()
    quirk_id, quirk = found
    fixed = {int(quirk.params[k]["tpdo"]) for k in ("cyclic", "polled") if k in quirk.params}
    if fixed:
        evidence.deviation(quirk_id, f"{quirk.title}: {', '.join(f'{c:04X}h' for c in sorted(fixed))} not used here")
    return fixed


def _configurable_tpdo(dut, sub: int, evidence) -> int:
    """The first TPDO whose communication sub-index ``sub`` is writable and which maps something."""
    fixed = _fixed_behaviour(dut, evidence)
    for comm in sorted(i for i in dut.profile.objects if 0x1800 <= i <= 0x19FF and i not in fixed):
        entry = dut.profile.entry(comm, sub)
        kind = dut.profile.entry(comm, 2)
        if entry is None or kind is None or not (entry.writable and kind.writable):
            continue
        if dut.read_uint(comm, 1) & 0x80000000:
            continue  # not valid
        if dut.profile.entry(comm + 0x200, 0) is not None and dut.read_uint(comm + 0x200, 0) == 0:
            continue  # nothing mapped
        return comm
    pytest.skip(f"not applicable: no TPDO with writable transmission type and sub-index {sub}")


def _start(dut):
    dut.nmt("start")


def test_sync_tpdo_sent_on_every_nth_sync(dut, settings_journal, back_to_preoperational, evidence):
    """Transmission type 3: the TPDO follows every third SYNC, so 9 SYNCs give exactly 3 frames."""
    if 3 not in dut.profile.capabilities.tpdo_transmission_types:
        pytest.skip("not applicable: transmission type 3 is not among the profile's accepted types")
    comm = _configurable_tpdo(dut, 2, evidence)
    cob_id = dut.read_uint(comm, 1) & 0x7FF
    settings_journal.write(comm, 2, b"\x03")
    _start(dut)
    mark = dut.frames.mark()
    for _ in range(9):
        dut.network.send_message(0x80, b"")
    window = dut.sdo_timeout + dut.profile.timing.nmt_settle_ms / 1000
    pdos = dut.frames.wait_count(lambda m: m.is_rx and m.arbitration_id == cob_id, 4, window, mark)
    evidence.measure(f"TPDO {cob_id:03X}h frames for 9 SYNCs", len(pdos), "frames", 3, 3)
    assert len(pdos) == 3, (
        f"{comm:04X}h.02 = 3: expected 3 TPDOs on {cob_id:03X}h for 9 SYNCs, observed {len(pdos)}\n"
        f"{format_frames(dut.frames.since(mark)[:20])}"
    )


def test_event_timer_period_within_tolerance(dut, settings_journal, back_to_preoperational, evidence):
    """Transmission type 255 with event timer T: the TPDO comes every T ms (>= 20 intervals, profile tolerance)."""
    if 255 not in dut.profile.capabilities.tpdo_transmission_types:
        pytest.skip("not applicable: transmission type 255 is not among the profile's accepted types")
    comm = _configurable_tpdo(dut, 5, evidence)
    cob_id = dut.read_uint(comm, 1) & 0x7FF
    timing = dut.profile.timing
    period = timing.heartbeat_test_period_ms
    settings_journal.write(comm, 2, b"\xff")
    settings_journal.write(comm, 5, period.to_bytes(2, "little"))
    _start(dut)
    mark = dut.frames.mark()
    count = timing.heartbeat_intervals + 1
    frames = dut.frames.wait_count(
        lambda m: m.is_rx and m.arbitration_id == cob_id, count, count * period * 1.5 / 1000 + 0.5, mark
    )
    assert len(frames) == count, f"only {len(frames)} of {count} TPDOs on {cob_id:03X}h with event timer {period} ms"
    stats = interval_stats([m.timestamp for m in frames], period)
    tolerance = timing.heartbeat_tolerance.allowed_ms(period)
    evidence.measure("event timer mean interval", round(stats.mean_ms, 3), "ms", period - tolerance, period + tolerance)
    allure.attach(stats.csv(), name="TPDO intervals.csv", attachment_type=allure.attachment_type.CSV)
    bad = stats.outside(tolerance)
    assert not bad, (
        f"{len(bad)} of {stats.count} intervals off by more than {tolerance:.1f} ms from {period} ms: "
        + ", ".join(f"#{n}: {i:.1f} ms" for n, i in bad[:8])
    )


def test_type_255_without_event_timer_sends_nothing(dut, settings_journal, back_to_preoperational, shaft, evidence):
    """Documented quirk: transmission type 255 with event timer 0 switches the TPDO off (no SYNC, no change)."""
    documented_quirk(dut, "transmission_type_255_timer_0_disables", evidence,
                     "CiA 301 type 255 without timer is event-driven")
    comm = _configurable_tpdo(dut, 5, evidence)
    cob_id = dut.read_uint(comm, 1) & 0x7FF
    settings_journal.write(comm, 2, b"\xff")
    settings_journal.write(comm, 5, b"\x00\x00")
    _start(dut)
    control = shaft
    if control is None:
        evidence.note("hardware: only SYNCs are sent; turn the shaft during the test to cover position changes")
    mark = pdo_stimulus(dut, control, 0.3)
    pdos = dut.frames.since(mark, lambda m: m.is_rx and m.arbitration_id == cob_id)
    evidence.measure(f"TPDO {cob_id:03X}h frames with type 255, timer 0", len(pdos), "frames", 0, 0)
    assert not pdos, (
        f"{comm:04X}h.02 = 255 and sub 5 = 0 must switch the TPDO off (documented); observed {len(pdos)} on "
        f"{cob_id:03X}h during 10 SYNCs{' and a turning shaft' if control else ''}:\n{format_frames(pdos[:5])}"
    )
