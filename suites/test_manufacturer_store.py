"""Store through manufacturer commands instead of (or besides) 1010h (documented quirks).

FRABA POSITAL: 2300h = 55 AA AA 55, no SDO confirmation, boot-up about 4 s later (UMD-CA §4.3,
§7.2.9). WayCon WCAN: 2105h 'save' stores 2100h..2104h, which 1010h does not (M §5). CiA 301
§7.5.2.13 has one store object, 1010h, with an SDO confirmation; the profiles document the
deviations and these tests check the device keeps its own promise.
"""

from __future__ import annotations

import pytest

from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.dut.store import changeable_parameter, other_valid_value
from encoder_conformance.plugin.skips import not_applicable
from encoder_conformance.plugin.suite_helpers import documented_quirk
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("manufacturer store commands (profile quirks store_reboots_without_reply, "
                                "manufacturer_store_object)"),
              pytest.mark.destructive]



@pytest.fixture
def reboot_store(dut):
    """The quirk of a device that stores through a manufacturer object and reboots instead of replying."""
    found = dut.profile.quirk(fx.StoreRebootsWithoutReply)
    if found is None:
        not_applicable("the device has no store-by-reboot command (quirk store_reboots_without_reply)")
    return found


def _store_by_reboot(dut, params: fx.StoreRebootsWithoutReply) -> None:
    """Send the store command; no SDO reply may come, and a boot-up must follow within store_max_ms."""
    request = sdo_frames.expedited_download_request(params.index, params.subindex, params.signature_bytes)
    request = bytes([0x22]) + request[1:]  # the manual's frame: download, size not indicated
    mark = dut.frames.mark()
    reply = dut.sdo_request(request, timeout=dut.sdo_silence_s)  # a reply that must not come: a silence window
    # the boot-up is waited for first: a failed check leaves the device up for the put-back that follows
    boot = dut.wait_bootup(mark, timeout=dut.profile.timing.store_max_ms / 1000)
    assert reply is None, f"documented: no SDO reply to the store command; observed {reply.describe()}"
    assert boot is not None, (
        f"no boot-up within {dut.profile.timing.store_max_ms:.0f} ms after the store command (the manual: reboot)"
    )


@pytest.mark.requires("preset")
def test_store_by_reboot_keeps_value(dut, reboot_store, evidence):
    """The manufacturer store command (no reply, reboot, boot-up) keeps a changed parameter: the device
    restarts from what it stored, so the value read after its boot-up is the stored one (no second reset)."""
    params = reboot_store.params
    evidence.deviation(reboot_store.id, reboot_store.quirk.title)
    found = changeable_parameter(dut.profile, lambda i, e: e.persisted_by == "manufacturer_store")
    if found is None:
        not_applicable("no parameter is declared persisted_by: manufacturer_store")
    original = dut.read(found.index, found.sub)
    dut.write(found.index, found.sub, found.new_value.to_bytes(len(original), "little"))
    try:
        _store_by_reboot(dut, params)
        observed = dut.read_uint(found.index, found.sub)
        assert observed == found.new_value, (
            f"{found.label}: stored {found.new_value}, {observed} after the reboot the store command causes")
    finally:
        if dut.usable:  # put the device back as it was, and store that
            dut.write(found.index, found.sub, original)
            _store_by_reboot(dut, params)


@pytest.fixture
def extra_store(dut, evidence):
    """The params of a second 'save' object for manufacturer parameters (quirk manufacturer_store_object)."""
    return documented_quirk(dut, fx.ManufacturerStoreObject, evidence, "1010h is the only store object",
                            needs=("test_object",))


def test_manufacturer_store_object_keeps_value(dut, extra_store, evidence):
    """A parameter saved with the manufacturer store object ('save') holds its new value after reset node."""
    index, sub = extra_store.test_object
    command = extra_store.key
    signature = extra_store.signature_bytes
    original = dut.read(index, sub)
    changed = other_valid_value(dut.profile, index, sub, int.from_bytes(original, "little"))
    assert changed is not None, f"{index:04X}h.{sub:02X}: no other valid value next to {original.hex()}"
    dut.write(index, sub, changed.to_bytes(len(original), "little"))
    try:
        dut.write(*command, signature)
        dut.nmt.reset_node()
        observed = dut.read_uint(index, sub)
        evidence.note(f"{index:04X}h.{sub:02X} = {changed}, {command[0]:04X}h 'save', reset node -> {observed}")
        assert observed == changed, (
            f"{index:04X}h.{sub:02X}: saved {changed} with {command[0]:04X}h, {observed} after reset node"
        )
    finally:
        if dut.usable:  # put the device back as it was, store that, and make it effective
            dut.write(index, sub, original)
            dut.write(*command, signature)
            dut.nmt.reset_node()
