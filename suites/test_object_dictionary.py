"""Object dictionary: every declared entry exists with its size, access and factory default.

CiA 301 §7.4 (object dictionary), §7.2.4.3.17 (abort codes); CTT cases OD 01-09, SDO 03-06.
"""

from __future__ import annotations

import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import ERROR_HISTORY, SdoAbortCode
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.plugin.skips import not_applicable
from encoder_conformance.plugin.suite_helpers import assert_abort, describe_value, expected_aborts
from encoder_conformance.profile import datatypes
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import resolve_node_id_expression

pytestmark = pytest.mark.spec("CiA 301 §7.4, §7.2.4.3.17")


def _read_or_fail(dut, index: int, sub: int) -> bytes:
    try:
        return dut.read(index, sub)
    except SdoAbortedError as exc:
        raise AssertionError(f"{index:04X}h.{sub:02X} declared readable but the read aborted: {exc}") from None


#: an error history entry above the count may hold no data (open reading error-history-empty-entry)
NO_DATA = ('CiA 301 v4.2.0 §7.5.2.4 (1003h sub 0: the number of errors recorded), §7.2.4.3.17 table 22 08000024h '
           '"No data available" (the CiA conformance test tool accepts it in Emergency 03)')


def _no_data_allowed(dut, index: int, sub: int, exc: SdoAbortedError) -> bool:
    """True where the read was refused with 08000024h for an error history entry above sub 0's count."""
    if index != ERROR_HISTORY or sub == 0 or exc.code != SdoAbortCode.NO_DATA:
        return False
    return sub > dut.read_uint(ERROR_HISTORY, 0)


def _read_or_no_data(dut, index: int, sub: int, evidence) -> bytes | None:
    """The entry's value, or None where the device has no data for it and CiA 301 allows it to say so."""
    try:
        return dut.read(index, sub)
    except SdoAbortedError as exc:
        if not _no_data_allowed(dut, index, sub, exc):
            raise AssertionError(f"{index:04X}h.{sub:02X} declared readable but the read aborted: {exc}") from None
    evidence.note(f"{index:04X}h.{sub:02X}: 08000024h (no data available), the error history counts fewer entries; "
                  f"allowed by {NO_DATA}")
    return None


def test_readable_entry_exists_with_declared_size(dut, readable_entry, evidence):
    """A readable entry answers an upload with exactly the size of its declared data type (an error history entry
    above the count may answer 08000024h instead, CiA 301 table 22)."""
    index, sub, _, entry = readable_entry
    data = _read_or_no_data(dut, index, sub, evidence)
    if data is None:
        evidence.rests_on("cia", NO_DATA)
        return
    size = datatypes.size_bytes(entry.type)
    if size is not None:
        assert len(data) == size, (
            f"{index:04X}h.{sub:02X} {entry.name}: {entry.type} is {size} bytes, the device sent {len(data)} "
            f"({data.hex(' ').upper()})"
        )


def test_read_only_entry_refuses_write(dut, read_only_entry, evidence):
    """Writing a ro/const entry (with its own current value; zeros where it holds no data) is refused with abort
    06010002h."""
    index, sub, _, entry = read_only_entry
    current = _read_or_no_data(dut, index, sub, evidence)
    if current is None:  # an empty error history entry: a write is refused as to any read-only entry
        current = bytes(datatypes.size_bytes(entry.type) or 4)
    payload = (current or b"\x00")[:4]
    response = dut.expect_abort(sdo_frames.expedited_download_request(index, sub, payload))
    assert_abort(dut, response, expected_aborts(dut, "write_ro", evidence), f"write to ro {index:04X}h.{sub:02X}")


def test_write_only_entry_refuses_read(dut, write_only_entry, evidence):
    """Reading a wo entry is refused with abort 06010001h."""
    index, sub, _, _ = write_only_entry
    response = dut.expect_abort(sdo_frames.upload_request(index, sub))
    assert_abort(dut, response, expected_aborts(dut, "read_wo", evidence), f"read of wo {index:04X}h.{sub:02X}")


def _undeclared_indices(profile) -> list[int]:
    """One index per area that the profile does not declare (communication, manufacturer, profile)."""
    picks = []
    for start, end in ((0x1000, 0x1FFF), (0x2000, 0x5FFF), (0x6000, 0x9FFF)):
        index = next((i for i in range(start + 0x80, end) if i not in profile.objects), None)
        if index is not None:
            picks.append(index)
    return picks


@pytest.mark.parametrize("area", ["communication", "manufacturer", "device profile"])
def test_undeclared_object_aborts(dut, area, evidence):
    """An upload of an object the device does not have is refused with abort 06020000h."""
    areas = ["communication", "manufacturer", "device profile"]
    picks = dict(zip(areas, _undeclared_indices(dut.profile), strict=False))
    index = picks[area]
    evidence.note(f"probed {index:04X}h")
    response = dut.expect_abort(sdo_frames.upload_request(index, 0))
    assert_abort(dut, response, expected_aborts(dut, "no_object", evidence), f"upload of absent {index:04X}h")


def _undeclared_subindex(profile) -> tuple[int, int]:
    """A sub-index past the last declared one of the first record, else sub 1 of the first VAR."""
    for index, obj in sorted(profile.objects.items()):
        if obj.subs is not None and max(obj.subs) < 0xFE:
            return index, max(obj.subs) + 1
    index = min(profile.objects)
    return index, 1


def test_undeclared_subindex_aborts(dut, evidence):
    """An upload of a sub-index the object does not have is refused with abort 06090011h."""
    index, sub = _undeclared_subindex(dut.profile)
    evidence.note(f"probed {index:04X}h.{sub:02X}")
    response = dut.expect_abort(sdo_frames.upload_request(index, sub))
    assert_abort(dut, response, expected_aborts(dut, "no_subindex", evidence), f"upload of {index:04X}h.{sub:02X}")


def _decode(entry, data: bytes):
    if entry.type == "VISIBLE_STRING":
        return data.rstrip(b"\x00")
    if entry.type in datatypes.STRING_TYPES:
        return data
    return int.from_bytes(data, "little", signed=datatypes.is_signed(entry.type))


def _expected(entry, node_id: int):
    """The default as the device sends it: bytes for strings (hex for OCTET_STRING), an int otherwise."""
    value = resolve_node_id_expression(entry.default, node_id)
    return datatypes.string_bytes(entry.type, value) if isinstance(value, str) else value


def test_factory_default(dut, default_entry, factory_state, evidence):
    """Right after restore-defaults and reset, each entry shows the factory default the manual gives."""
    index, sub, _, entry = default_entry
    source = entry.manual or f"profile {dut.profile.id}"
    evidence.rests_on("cia" if source.startswith("CiA") else "manual", source)
    excluded = dut.profile.quirk(fx.RestoreExcludes)
    if excluded is not None and index in excluded.params.indices:
        not_applicable(f"restore-defaults leaves {index:04X}h as it was (quirk {excluded.id})")
    expected = _expected(entry, dut.node_id)
    observed = _decode(entry, _read_or_fail(dut, index, sub))
    if _zero_padded(observed, expected):
        evidence.note(f"{index:04X}h.{sub:02X}: the default fills the first {len(expected)} of {len(observed)} "
                      "bytes, the rest read 00h (an EDS or manual string default gives no object length, CiA 306)")
        return
    assert observed == expected, (
        f"{index:04X}h.{sub:02X} {entry.name}: default {describe_value(expected)} ({entry.manual}), "
        f"observed {describe_value(observed)}"
    )


def _zero_padded(observed: object, expected: object) -> bool:
    """A string or octet string longer than its default only by 00h bytes: a fixed-size object holding it."""
    if isinstance(observed, bytes) and isinstance(expected, bytes) and len(observed) > len(expected):
        return observed.startswith(expected) and not observed[len(expected):].strip(b"\x00")
    if isinstance(observed, str) and isinstance(expected, str) and len(observed) > len(expected):
        return observed.startswith(expected) and not observed[len(expected):].strip("\x00")
    return False


def test_heartbeat_time_reads_back_written_value(dut, settings_journal):
    """A value written to a rw entry (1017h) reads back unchanged (CTT OD 09)."""
    entry = dut.profile.entry(0x1017, 0)
    if entry is None or not entry.writable:
        not_applicable("the profile declares no writable 1017h")
    value = 1234 if entry.max is None or entry.max >= 1234 else entry.max
    settings_journal.write(0x1017, 0, value.to_bytes(2, "little"))
    observed = dut.read_uint(0x1017)
    assert observed == value, f"1017h: wrote {value}, read back {observed}"
