"""One test per class of defect issue 9 found when drafting profiles from real vendor EDS files.

tests/data/eds/drive_oddities.eds and encoder_oddities.eds are small files written to show each oddity;
their header comments list them. Every test here failed before the fix it names.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from pydantic import ValidationError

from encoder_conformance.profile import datatypes
from encoder_conformance.profile.eds import export_eds, profile_draft_from_eds, write_profile_draft
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.od_builder import initial_value
from encoder_conformance.profile.schema import EntrySpec

EDS = Path(__file__).parent / "data" / "eds"
DRIVE, ENCODER = EDS / "drive_oddities.eds", EDS / "encoder_oddities.eds"


def _drafted(eds: Path, folder: Path):
    """(draft dict, todos, loaded profile) of ``eds``, written and validated as `from-eds` does."""
    draft, todos = profile_draft_from_eds(eds)
    out = folder / f"{draft['id']}.yaml"
    write_profile_draft(draft, out, todos)
    return draft, todos, load_profile(str(out)).profile


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    return _drafted(DRIVE, tmp_path_factory.mktemp("drive"))


@pytest.fixture(scope="module")
def encoder(tmp_path_factory):
    return _drafted(ENCODER, tmp_path_factory.mktemp("encoder"))


def _cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "encoder_conformance", "profile", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=60)


def test_cia_profile_comes_from_1000h_not_from_the_object_range(drive, encoder):
    """A CiA 402 drive with objects in 6000h..65FFh is not drafted as a multi-turn encoder with preset."""
    _, todos, profile = drive
    caps = profile.capabilities
    assert (caps.cia406, caps.encoder, caps.multiturn, caps.preset, caps.scaling) == (False,) * 5
    assert any("names CiA profile 402" in todo for todo in todos)
    single = encoder[2].capabilities
    assert (single.cia406, single.encoder, single.multiturn) == (True, True, False)  # 1000h = 0x00010196


def test_identity_placeholders_and_missing_sub_indices(drive, encoder):
    """1018h sub 1 = 0 takes [DeviceInfo] VendorNumber (and the twin reports it); no 1018h sub 2: no product
    code to check, though [DeviceInfo] has one; 1018h sub 3 = 0 takes RevisionNumber."""
    _, todos, profile = drive
    assert profile.identity.vendor_id == 0x1234
    assert profile.entry(0x1018, 1).default == 0x1234
    assert profile.identity.product_code is None
    assert any("1018h has no sub 2" in todo for todo in todos)
    revision = encoder[2].identity.revision
    assert (revision.min, revision.max) == (0x30001, 0x30001)


def test_octet_string_default_is_bytes(drive):
    _, _, profile = drive
    entry = profile.entry(0x2000, 0)
    assert entry.type == "OCTET_STRING"
    assert datatypes.string_bytes(entry.type, entry.default) == b"\xc8\x3d\xbb"
    with pytest.raises(ValidationError, match="is not hex bytes"):
        EntrySpec(name="key", type="OCTET_STRING", access="ro", default="C83DBG")


def test_error_history_count_is_writable_and_dynamic(drive):
    """1003h from CompactSubObj: sub 0 counts the errors (rw, 0 clears), not a read-only 'highest sub-index' 8."""
    _, _, profile = drive
    count = profile.entry(0x1003, 0)
    assert count.access == "rw"
    assert count.dynamic
    assert count.default is None


def test_tpdo_without_type_or_mapping_is_a_todo(drive):
    _, todos, _ = drive
    assert any(todo.startswith("TPDO 1801h: the EDS gives no transmission type") for todo in todos)


def test_serial_number_objects_are_per_unit_and_agree(encoder):
    _, _, profile = encoder
    assert profile.entry(0x650B, 0).per_unit
    assert profile.entry(0x1018, 4).per_unit
    in_650b = initial_value(profile, 0x650B, 0, profile.entry(0x650B, 0), 1)
    assert in_650b == initial_value(profile, 0x1018, 4, profile.entry(0x1018, 4), 1)


def test_unknown_data_type_is_a_todo(drive):
    _, todos, profile = drive
    assert profile.entry(0x2001, 0).type == "DOMAIN"
    assert any("data type 0x0020 is not a CiA 301 basic type" in todo for todo in todos)


def test_persistence_is_drafted_from_1010h(drive):
    """1010h subs 1..3: communication values store with sub 2, application values with sub 3."""
    _, todos, profile = drive
    assert profile.entry(0x1017, 0).persisted_by == "store_comm"
    assert profile.entry(0x1800, 2).persisted_by == "store_comm"
    assert profile.entry(0x1010, 1).persisted_by == "none"  # the command itself is not stored
    assert any(todo.startswith("objects.persisted_by:") for todo in todos)


def test_to_eds_keeps_order_code_and_granularity_and_writes_no_placeholders(drive, tmp_path):
    _, _, profile = drive
    text = export_eds(profile, tmp_path / "drive.eds").read_text(encoding="utf-8")
    assert "OrderCode=XD-402-CO-7" in text
    assert "Granularity=8" in text
    nameless = profile.model_copy(update={"identity": profile.identity.model_copy(update={"vendor_name": ""})})
    assert "TODO" not in export_eds(nameless, tmp_path / "nameless.eds").read_text(encoding="utf-8")


def test_draft_lists_todos_for_validate_and_reports(drive, tmp_path):
    draft, todos, profile = drive
    assert profile.todo == [" ".join(t.split()) for t in todos]
    out = tmp_path / f"{draft['id']}.yaml"
    write_profile_draft(draft, out, todos)
    listed = _cli("validate", "--todo", str(out))
    assert listed.returncode == 0, listed.stderr
    assert f"{len(todos)} assumptions unconfirmed" in listed.stdout
    assert "  TODO 1: " in listed.stdout


def test_from_eds_command_line(tmp_path):
    """-o without --id gives the id of the file name; an existing file is kept; a missing EDS is one line."""
    done = _cli("from-eds", str(DRIVE), "-o", str(tmp_path / "other.yaml"))
    assert done.returncode == 0, done.stderr
    assert _cli("validate", str(tmp_path / "other.yaml")).returncode == 0
    again = _cli("from-eds", str(DRIVE), "-o", str(tmp_path / "other.yaml"))
    assert again.returncode == 4
    assert "exists; not overwritten" in again.stderr
    assert _cli("from-eds", str(DRIVE), "-o", str(tmp_path / "other.yaml"), "--force").returncode == 0
    missing = _cli("from-eds", str(tmp_path / "nothere.eds"))
    assert missing.returncode == 4
    assert "Traceback" not in missing.stderr
    assert "no such file" in missing.stderr


@pytest.mark.parametrize(("content", "message"), [
    (b"", "the file is empty"),
    (bytes(range(256)) * 4, "binary data"),
    (b"[FileInfo]\r\nFileName=x.eds\r\n[DeviceInfo]\r\nVendorName=X\r\n", "lacks the objects every CANopen device has"),
])
def test_files_that_are_no_eds_are_refused(tmp_path, content: bytes, message: str):
    eds = tmp_path / "broken.eds"
    eds.write_bytes(content)
    done = _cli("from-eds", str(eds), "-o", str(tmp_path / "broken.yaml"))
    assert done.returncode == 1
    assert message in done.stderr
    assert not (tmp_path / "broken.yaml").exists()
