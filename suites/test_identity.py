"""Identity and device type: 1000h, 1008h, 1018h (CiA 301 §7.5.2.1, §7.5.2.9, §7.5.2.23)."""

from __future__ import annotations

import pytest

from encoder_conformance.dut.sdo import NO_SERIAL, read_identity, serial_650b_key
from encoder_conformance.plugin.skips import not_applicable, not_selected
from encoder_conformance.plugin.suite_helpers import describe_value
from encoder_conformance.profile import datatypes

pytestmark = pytest.mark.spec("CiA 301 §7.5.2")


def _expect(value, what: str, reason: str):
    if value is None:
        not_applicable(f"the profile gives no {what} ({reason})")
    return value


@pytest.mark.spec("CiA 301 §7.5.2.1 (1000h device type)")
def test_device_type_matches_profile(dut, evidence):
    """1000h reads the device type the profile declares (profile number + encoder type)."""
    expected = _expect(dut.profile.identity.device_type, "device type", "identity.device_type")
    observed = dut.read_uint(0x1000)
    assert observed == expected, f"1000h: expected {describe_value(expected)}, observed {describe_value(observed)}"


@pytest.mark.spec("CiA 301 §7.5.2.9 (1008h manufacturer device name)")
def test_device_name_matches_profile(dut):
    """1008h reads the manufacturer device name the profile declares."""
    expected = _expect(dut.profile.identity.device_name, "device name", "identity.device_name")
    observed = dut.read(0x1008).rstrip(b"\x00")
    wanted = datatypes.string_bytes("VISIBLE_STRING", expected)
    assert observed == wanted, f"1008h: expected {expected!r} ({wanted.hex(' ')}), observed {observed!r}"


@pytest.mark.spec("CiA 301 §7.5.2.23 (1018h sub 1 vendor-ID)")
def test_vendor_id_matches_profile(dut):
    """1018h sub 1 holds the CiA-assigned vendor-ID of the manufacturer."""
    expected = _expect(dut.profile.identity.vendor_id, "vendor-ID", "identity.vendor_id")
    observed = dut.read_uint(0x1018, 1)
    assert observed == expected, f"1018h.01: expected {describe_value(expected)}, observed {describe_value(observed)}"


@pytest.mark.spec("CiA 301 §7.5.2.23 (1018h sub 2 product code)")
def test_product_code_matches_profile(dut):
    """1018h sub 2 holds the product code the profile declares."""
    expected = _expect(dut.profile.identity.product_code, "product code", "identity.product_code")
    observed = dut.read_uint(0x1018, 2)
    assert observed == expected, f"1018h.02: expected {describe_value(expected)}, observed {describe_value(observed)}"


@pytest.mark.spec("CiA 301 §7.5.2.23 (1018h sub 3 revision number)")
def test_revision_number_in_declared_range(dut, evidence):
    """1018h sub 3 lies in the revision range the manual covers."""
    revision = _expect(dut.profile.identity.revision, "revision range", "identity.revision")
    observed = dut.read_uint(0x1018, 3)
    evidence.note(f"revision number 0x{observed:08X}")
    assert revision.min <= observed <= revision.max, (
        f"1018h.03: 0x{observed:08X} is outside the range the profile covers "
        f"(0x{revision.min:08X}..0x{revision.max:08X}); a firmware the manual does not describe"
    )


@pytest.mark.spec("CiA 301 §7.5.2.23 (1018h sub 0 highest sub-index)")
def test_identity_record_size(dut):
    """1018h sub 0 equals the highest identity sub-index the profile declares."""
    entry = dut.profile.entry(0x1018, 0)
    if entry is None or entry.default is None:
        not_applicable("the profile declares no 1018h sub 0 value")
    observed = dut.read_uint(0x1018, 0)
    assert observed == entry.default, f"1018h.00: expected {entry.default}, observed {observed}"


@pytest.mark.spec("CiA 406 650Bh / CiA 301 1018h sub 4 (serial number)")
def test_serial_number_consistent(dut, evidence):
    """The serial number in 1018h sub 4 equals the one in 650Bh where the device has both."""
    profile = dut.profile
    if profile.entry(0x1018, 4) is None:
        not_applicable("the profile declares no 1018h sub 4 serial number")
    serial = dut.read_uint(0x1018, 4)
    evidence.note(f"serial number {serial}")
    other = serial_650b_key(profile)
    if not other:
        not_applicable("the profile declares no 650Bh serial number to compare with")
    observed = dut.read_uint(*other)
    assert observed == serial, f"650Bh.{other[1]:02X} = {observed} but 1018h.04 = {serial}"




@pytest.mark.spec("CiA 301 §7.5.2.23 (1018h sub 4 serial number)")
def test_serial_number_format(dut, evidence):
    """1018h sub 4 has the format the manual states (identity.serial_format); where it states none, a value a
    device without a serial number would not show (neither 0 nor FFFFFFFFh: our reading, a warning only)."""
    if dut.profile.entry(0x1018, 4) is None:
        not_applicable("the profile declares no 1018h sub 4 serial number")
    serial = dut.read_uint(0x1018, 4)
    evidence.note(f"serial number {serial} (0x{serial:08X})")
    wanted = dut.profile.identity.serial_format
    if wanted is None:
        if serial in NO_SERIAL:
            evidence.inferred_problem(f"1018h.04 = 0x{serial:08X}, what a device without a serial number reads",
                                      "a delivered unit has a serial number other than 0 and FFFFFFFFh (our reading)")
        return
    evidence.rests_on("manual", wanted.manual)
    assert wanted.matches(serial), (
        f"1018h.04 = {serial} does not have the format the manual states ({wanted.pattern!r}, {wanted.manual})")


@pytest.mark.spec("CiA 301 §7.5.2.23 (1018h sub 4 serial number) / CiA 406 650Bh")
def test_serial_number_matches_label(dut, evidence, label_serial):
    """The unit reports the serial number printed on its label (1018h sub 4, else 650Bh): goods-in checks that
    the device on the bench is the unit it books in."""
    if label_serial is None:
        not_selected("no label serial number given (--label-serial)")
    label, source = label_serial
    identity = read_identity(dut)
    if identity.unit_serial is None:
        not_applicable("the device reports no serial number (no 1018h sub 4, no 650Bh); "
                    f"label {label} ({source})")
    where = "1018h.04" if identity.serial is not None else "650Bh"
    evidence.note(f"label {label} ({source}); device {where} = {identity.unit_serial}")
    assert identity.unit_serial == label, (
        f"{where} = {identity.unit_serial} but the label says {label} ({source}): another unit, or a wrong serial")
