"""Store (1010h) and restore default (1011h) parameters (CiA 301 §7.5.2.13, §7.5.2.14; CTT 8.1-8.9)."""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import LOAD, SAVE
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.dut.store import STORE_GROUPS, CannotPersist, changeable_parameter, other_valid_value
from encoder_conformance.plugin.skips import not_applicable
from encoder_conformance.plugin.suite_helpers import assert_abort, documented_quirk, expected_aborts
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("CiA 301 §7.5.2.13/§7.5.2.14"), pytest.mark.destructive]



def _store(dut, index: int, sub: int) -> str:
    """1010h sub 1 'save' where the device has it, else the entry's own way (e.g. stored by itself)."""
    entry = dut.profile.entry(index, sub)
    if 1 in dut.profile.capabilities.store_subindices and entry.persisted_by in STORE_GROUPS:
        dut.write(0x1010, 1, SAVE)
        return "1010h.01 'save'"
    return dut.store.persist(index, sub)


@pytest.fixture
def stored_change(dut, settings_journal, evidence):
    """Change one storable parameter and store it; afterwards put the old value back and store again."""
    found = changeable_parameter(dut.profile, lambda i, e: e.persisted_by in (*STORE_GROUPS, "auto"), prefer=(0x1017,))
    if found is None:
        not_applicable("the profile declares no storable parameter with a default")
    index, sub, entry, value = found.index, found.sub, found.entry, found.new_value
    original = dut.read(index, sub)
    settings_journal.write(index, sub, value.to_bytes(len(original), "little"))
    try:
        how = _store(dut, index, sub)
    except CannotPersist as exc:
        not_applicable(f"{exc}")
    evidence.note(f"{found.label} = {value}, stored with {how}")
    yield index, sub, entry, value
    if dut.usable:
        dut.write(index, sub, original)
        _store(dut, index, sub)


def test_stored_value_survives_reset_node(dut, stored_change):
    """A stored value (1010h sub 1 'save', or stored by the device itself) is still there after NMT reset node."""
    index, sub, entry, value = stored_change
    dut.nmt.reset_node()
    observed = dut.read_uint(index, sub)
    assert observed == value, f"{index:04X}h.{sub:02X} {entry.name}: stored {value}, {observed} after reset node"


def test_stored_value_survives_power_cycle(dut, stored_change, power_cycle):
    """A stored value (1010h sub 1 'save', or stored by the device itself) survives switching the power off and on."""
    index, sub, entry, value = stored_change
    power_cycle()
    observed = dut.read_uint(index, sub)
    assert observed == value, f"{index:04X}h.{sub:02X} {entry.name}: stored {value}, {observed} after power cycle"


@pytest.mark.requires("restore_subindices")
def test_restore_defaults_effective_after_reset(dut, stored_change):
    """After 1011h sub 1 'load' and reset node, the stored value is replaced by the factory default."""
    index, sub, entry, _ = stored_change
    excluded = dut.profile.quirk(fx.RestoreExcludes)
    if excluded is not None and index in excluded.params.indices:
        not_applicable(f"restore leaves {index:04X}h unchanged (quirk {excluded.id})")
    dut.write(0x1011, 1, LOAD)
    dut.nmt.reset_node()
    observed = dut.read_uint(index, sub)
    assert observed == entry.default, (
        f"{index:04X}h.{sub:02X}: {observed} after restore + reset, expected the default {entry.default}"
    )


@pytest.mark.parametrize(
    ("index", "name"), [(0x1010, "store"), (0x1011, "restore")], ids=["1010h store", "1011h restore"]
)
def test_wrong_signature_refused(dut, index, name, evidence):
    """A store/restore command without the 'save'/'load' signature is refused with abort 08000020h."""
    capabilities = dut.profile.capabilities
    subs = capabilities.store_subindices if index == 0x1010 else capabilities.restore_subindices
    if not subs:
        not_applicable(f"the profile declares no {name} sub-indices")
    response = dut.expect_abort(sdo_frames.expedited_download_request(index, subs[0], b"SAVE"))
    assert_abort(dut, response, expected_aborts(dut, "store_signature", evidence),
                 f"{name} {index:04X}h.{subs[0]:02X} with signature 'SAVE'")



@pytest.fixture
def reload_quirk(dut, evidence):
    """The params of a device whose 1011h sub-indices load saved values at once (quirk reload_immediate)."""
    return documented_quirk(dut, fx.ReloadImmediate, evidence, "every restore acts after a reset",
                            needs=("test_object",))


def test_reload_takes_effect_without_reset(dut, reload_quirk, settings_journal, evidence):
    """Each documented reload sub: save, change, 1011h 'load' -> the saved value is back at once, no reset."""
    index, sub = reload_quirk.test_object
    failures = []
    for reload_sub, save_sub in sorted(reload_quirk.reload_immediate.items()):
        saved = dut.read_uint(index, sub)
        changed = other_valid_value(dut.profile, index, sub, saved)
        assert changed is not None, f"{index:04X}h.{sub:02X}: no other valid value next to {saved}"
        size = len(dut.read(index, sub))
        dut.write(0x1010, save_sub, SAVE)
        settings_journal.write(index, sub, changed.to_bytes(size, "little"))
        dut.write(0x1011, reload_sub, LOAD)
        observed = dut.read_uint(index, sub)
        evidence.note(f"1010h.{save_sub:02X} saved {saved}, changed to {changed}, "
                      f"1011h.{reload_sub:02X} 'load' -> {observed}")
        if observed != saved:
            failures.append(f"1011h.{reload_sub:02X} (loads what 1010h.{save_sub:02X} saved): {index:04X}h.{sub:02X} "
                            f"reads {observed}, expected the saved {saved} at once")
    assert not failures, "documented immediate reload did not act:\n" + "\n".join(failures)
