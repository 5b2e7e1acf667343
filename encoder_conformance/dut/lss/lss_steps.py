"""Steps of the LSS suite on an ``LssDevice``: bit-timing activation, the node-ID life cycle through a power cycle,
and what the profile's LSS quirks say about the result."""

from __future__ import annotations

from encoder_conformance.dut.link.frames import Mark, format_frames
from encoder_conformance.dut.lss.lss_device import LssDevice, expect_success
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import resolve_node_id_expression

SWITCH_DELAY_MS = 100


def activate(lss: LssDevice, index: int) -> tuple[Mark, float]:
    """Configure bit timing ``index`` and activate it with SWITCH_DELAY_MS, the device still in the configuration
    state (the LSS FSA has activate bit timing there; open reading lss-activate-bit-timing-state); the mark
    before it and the delay. The caller leaves the configuration state after the switch (no master frame within
    it)."""
    lss.transition("configuration")
    expect_success(lss.master.configure_bit_timing(index), f"configure bit timing {index}")
    return lss.master.activate_bit_timing(SWITCH_DELAY_MS), SWITCH_DELAY_MS / 1000


def manual_excludes(device: LssDevice, node_id: int) -> tuple[int, int] | None:
    """The manual's configure node-ID range where it leaves ``node_id`` out (quirk lss_node_id_range), else None."""
    quirk = device.dut.profile.params_of(fx.LssNodeIdRange)
    if quirk is None or quirk.node_id_range[0] <= node_id <= quirk.node_id_range[1]:
        return None
    return quirk.node_id_range


def cob_ids_not_reset(lss: LssDevice) -> list[str]:
    """Quirk unconfigured_node_id: the COB-IDs it lists that do not hold their default for the node-ID given."""
    quirk = lss.dut.profile.params_of(fx.UnconfiguredNodeId)
    problems = []
    for key in () if quirk is None else quirk.cob_ids_reset_to_default:
        entry = lss.dut.profile.entry(key.index, key.sub)
        if entry is None or entry.default is None:
            continue
        expected = resolve_node_id_expression(entry.default, lss.node_id)
        value = lss.dut.read_uint(key.index, key.sub)
        if value != expected:
            problems.append(f"{key}: 0x{value:X} after the node-ID was given, its default is 0x{expected:X}")
    return problems


def stored_node_id_survives_power_cycle(lss: LssDevice, store: bool) -> None:
    """Configure another node-ID (and store it), power cycle: the device boots with it; then the same way
    back to the node-ID it was found at (AssertionError where it does not)."""
    new_id = lss.free_node_id()
    for node_id, at in ((new_id, lss.node_id), (lss.node_id, new_id)):
        lss.into_lss_state(at)  # after the power cycle a device may have started itself
        expect_success(lss.configure_for(node_id), f"configure node-ID {node_id}")
        if store:
            expect_success(lss.master.store_configuration(), "store configuration")
        lss.leave()
        mark = lss.power_cycle()  # type: ignore[misc]  # why: its tests ask for power_cycle (skipped without a switch)
        assert lss.wait_bootup_at(node_id, mark) is not None or lss.answers_at(node_id), (
            f"after a power cycle the device is not at the stored node-ID {node_id}\n"
            f"{format_frames(lss.dut.frames.since(mark)) or '  no frames'}")
