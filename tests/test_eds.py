"""EDS import (with vendor oddities), profile drafts and export -> import round trips."""

from __future__ import annotations

import configparser
from pathlib import Path

import canopen
import pytest
import yaml

from encoder_conformance.errors import ProfileError
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.eds import (
    clean_eds,
    export_eds,
    normalise_node_id_formula,
    objects_from_eds,
    parse_number,
    profile_draft_from_eds,
    read_eds,
    write_profile_draft,
)
from encoder_conformance.profile.loader import iter_profile_ids, load_profile
from encoder_conformance.profile.schema import DeviceProfile

EDS_DIR = Path(__file__).parent / "data" / "eds"
FIXTURES = sorted(p.name for p in EDS_DIR.glob("*.eds"))


def signature(objects: dict[int, dict]) -> dict[tuple[int, int], tuple[str, str]]:
    """(index, sub) -> (canonical type, access) of profile-shaped objects."""
    result = {}
    for index, obj in objects.items():
        for sub, entry in obj.get("subs", {0: obj}).items():
            result[(index, sub)] = (datatypes.canonical_name(entry["type"]), entry["access"])
    return result


def profile_signature(profile: DeviceProfile) -> dict[tuple[int, int], tuple[str, str]]:
    return {
        (index, sub): (datatypes.canonical_name(entry.type), entry.access)
        for index, sub, _obj, entry in profile.iter_entries()
    }


def entry_of(objects: dict[int, dict], index: int, sub: int = 0) -> dict:
    obj = objects[index]
    return obj["subs"][sub] if "subs" in obj else obj


def has(entry: dict, expected: dict) -> bool:
    """True if ``entry`` holds every key/value of ``expected``."""
    return entry.items() >= expected.items()


def draft_profile(name: str, tmp_path: Path) -> tuple[DeviceProfile, list[str], str]:
    """Draft from a fixture, written as YAML and validated from the YAML text."""
    draft, todos = profile_draft_from_eds(EDS_DIR / name)
    out = tmp_path / f"{draft['id']}.yaml"
    write_profile_draft(draft, out, todos)
    text = out.read_text(encoding="utf-8")
    return DeviceProfile.model_validate(yaml.safe_load(text)), todos, text


# --------------------------------------------------------------------------- helpers


@pytest.mark.parametrize(
    ("text", "value"),
    [("0x1A", 26), ("1Ah", 26), ("26", 26), ("026", 26), ("TRUE", 1), ("no", 0), ("-5", -5), ("", None),
     ("abc", None), ("$NODEID+1", None)],
)  # fmt: skip
def test_parse_number(text, value):
    assert parse_number(text) == value


@pytest.mark.parametrize(
    ("text", "formula"),
    [("$NODEID+0x180", "$NODEID+0x180"), ("$NodeId + 384", "$NODEID+0x180"),
     ("0x180+$NODEID", "$NODEID+0x180"), ("$NODEID", "$NODEID+0x0"), ("0x180", None)],
)  # fmt: skip
def test_node_id_formula(text, formula):
    assert normalise_node_id_formula(text) == formula


# --------------------------------------------------------------------------- import of each fixture


@pytest.mark.parametrize("name", FIXTURES)
def test_every_fixture_imports(name):
    objects = objects_from_eds(EDS_DIR / name)
    assert {0x1000, 0x1001, 0x1018} <= objects.keys()
    assert all(index >= 0x1000 for index in objects)  # DummyXXXX and type definitions skipped
    assert all(entry["manual"].startswith(f"EDS {name} [") for entry in (objects[0x1000], objects[0x1018]))


def test_clean_encoder(tmp_path):
    result = read_eds(EDS_DIR / "clean_encoder.eds")
    assert result.fixes == []
    assert result.notes == []
    objects = result.objects
    assert objects[0x1000] == {
        "name": "Device type",
        "type": "U32",
        "access": "ro",
        "default": 0x00020196,
        "manual": "EDS clean_encoder.eds [1000]",
    }
    assert entry_of(objects, 0x1018, 0)["access"] == "const"
    assert entry_of(objects, 0x1018, 4).get("default") is None
    assert objects[0x1010]["kind"] == "array"
    assert "kind" not in objects[0x1018]
    assert entry_of(objects, 0x1800, 2) == {
        "name": "Transmission type",
        "type": "U8",
        "access": "rw",
        "default": 254,
        "min": 0,
        "max": 255,
        "manual": "EDS clean_encoder.eds [1800sub2]",
    }
    assert entry_of(objects, 0x6004)["pdo_mappable"] is True
    assert entry_of(objects, 0x1008)["default"] == "EX58-MT"
    assert entry_of(objects, 0x6030, 1)["type"] == "I16"


def test_dummy_usage_missing_entries():
    path = EDS_DIR / "dummy_usage_missing.eds"
    with pytest.raises(configparser.NoOptionError):  # the oddity this fixture exists for
        canopen.import_od(str(path))
    result = read_eds(path)
    assert any(
        "[DummyUsage] added missing Dummy0001, Dummy0002, Dummy0003, Dummy0004" in f for f in result.fixes
    )
    assert 0x6004 in result.objects
    assert all(index >= 0x1000 for index in result.objects)


def test_node_id_formulas_are_kept():
    result = read_eds(EDS_DIR / "nodeid_formulas.eds")
    objects = result.objects
    assert entry_of(objects, 0x1014)["default"] == "$NODEID+0x80"
    assert entry_of(objects, 0x1200, 1)["default"] == "$NODEID+0x600"
    assert entry_of(objects, 0x1200, 2)["default"] == "$NODEID+0x580"  # written as $NODEID+1408
    assert entry_of(objects, 0x1400, 1)["default"] == "$NODEID+0x200"  # '$NodeId + 0x200'
    assert entry_of(objects, 0x1800, 1)["default"] == "$NODEID+0x40000180"  # '0x40000180+$NODEID'
    assert entry_of(objects, 0x1801, 1)["default"] == "$NODEID+0xC0000280"
    assert any("'0x40000180+$NODEID' written as '$NODEID+0x40000180'" in f for f in result.fixes)


def test_compact_sub_obj_is_expanded():
    path = EDS_DIR / "compact_subobj.eds"
    with pytest.raises(configparser.NoOptionError):  # canopen cannot read a sparse [xxxxName]
        canopen.import_od(str(path))
    result = read_eds(path)
    objects = result.objects
    assert objects[0x1016]["kind"] == "array"
    assert sorted(objects[0x1016]["subs"]) == [0, 1, 2]  # no [1016Name]: canopen alone gives sub 0..1
    assert has(entry_of(objects, 0x1016, 0), {"type": "U8", "access": "ro", "default": 2})
    assert has(entry_of(objects, 0x1016, 2), {"type": "U32", "access": "rw", "default": 0})
    assert [entry_of(objects, 0x6300, s)["name"] for s in (1, 2)] == [
        "Cam state channel 1",
        "Cam state channel 2",
    ]
    assert entry_of(objects, 0x6300, 1)["pdo_mappable"] is True
    assert entry_of(objects, 0x6301, 1)["name"] == "Cam enable register 1"
    assert entry_of(objects, 0x6301, 2)["name"] == "Cam enable channel 2"
    assert entry_of(objects, 0x6310, 1)["default"] == 0
    assert entry_of(objects, 0x6310, 2)["default"] == -100  # [6310Value] 0xFFFFFF9C as INTEGER32
    assert entry_of(objects, 0x6300, 2)["manual"] == "EDS compact_subobj.eds [6300Name]"
    assert sum("CompactSubObj=2" in f for f in result.fixes) == 4


def test_odd_formatting():
    path = EDS_DIR / "odd_formatting.eds"
    assert path.read_bytes().startswith(b"\xef\xbb\xbf")
    with pytest.raises(configparser.Error):
        canopen.import_od(str(path))
    result = read_eds(path)
    fixes = "\n".join(result.fixes)
    for expected in (
        "removed the UTF-8 byte-order mark",
        "section [DEVICEINFO] renamed to [DeviceInfo]",
        "section [1018SUB0] renamed to [1018sub0]",
        "section [6004] appears more than once",
        "[6001] AccessType given twice",
        "[1001] key casing: parametername -> ParameterName",
        "[Comments] added empty Line3",
        "[1000] ObjectType='07' rewritten as 7",
        "dropped data-type definition / dummy sections [0002]",
    ):
        assert expected in fixes
    objects = result.objects
    assert result.device_info["VendorNumber"] == "0x00abcdef"
    assert result.device_info["ProductName"] == "EX58-ODD"  # inline comment removed
    assert entry_of(objects, 0x1000)["default"] == 0x00020196
    assert has(entry_of(objects, 0x1001), {"access": "ro", "pdo_mappable": True})
    assert sorted(objects[0x1018]["subs"]) == [0, 1, 2]  # sub-section before its object
    assert has(entry_of(objects, 0x1018, 0), {"access": "const", "default": 2})
    assert entry_of(objects, 0x1014)["default"] == "$NODEID+0x80"
    assert entry_of(objects, 0x6001)["access"] == "rw"  # the later duplicate key wins
    assert entry_of(objects, 0x6001)["name"] == "Measuring units per revolution (°)"
    assert entry_of(objects, 0x6004)["pdo_mappable"] is True  # from the duplicated section
    speed = entry_of(objects, 0x6030, 1)
    assert (speed["default"], speed["min"], speed["max"]) == (-1, -32768, 32767)  # hex two's complement
    assert "default" not in entry_of(objects, 0x1009)  # empty DefaultValue


def test_cleaned_text_is_readable_by_canopen(tmp_path):
    for name in FIXTURES:
        cleaned = clean_eds((EDS_DIR / name).read_bytes())
        copy = tmp_path / name
        copy.write_text(cleaned.text, encoding="utf-8")
        with copy.open(encoding="utf-8") as fp:
            assert 0x1018 in canopen.import_od(fp)


MORE_ODDITIES = """[DeviceInfo]
VendorName=M\u00fcller Sensorik
ProductName=X1
RevisionNumber=
LSS_Supported=yes
[DeviceCommissioning]
NodeID=0x20
Baudrate=250
[1000]
ParameterName=Device type
DataType=0x0007
AccessType=ro
DefaultValue=0x00010196
[1001]
ParameterName=Error register
DataType=0x0005
[1018]
ParameterName=Identity
[1018sub0]
ParameterName=Highest sub-index supported
DataType=0x0005
AccessType=ro
DefaultValue=1
[1018sub1]
ParameterName=Vendor-ID
DataType=0x0007
AccessType=ro
DefaultValue=5
[1200sub1]
ParameterName=Orphan
DataType=0x0007
AccessType=ro
[2001]
ParameterName=Time of day
DataType=0x000C
AccessType=rw
[2002]
ParameterName=Gain
DataType=0x0008
AccessType=rw
DefaultValue=1.5
LowLimit=0.5
[2003]
ParameterName=Too big
DataType=0x0005
AccessType=rw
DefaultValue=300
[2004]
ParameterName=Empty record
ObjectType=0x9
"""


def test_more_oddities(tmp_path):
    path = tmp_path / "latin1.eds"
    path.write_bytes(MORE_ODDITIES.encode("latin-1"))
    result = read_eds(path)
    fixes, notes = "\n".join(result.fixes), "\n".join(result.notes)
    assert "decoded as Windows-1252" in fixes
    assert result.device_info["VendorName"] == "M\u00fcller Sensorik"
    assert "[DeviceCommissioning] renamed to [DeviceComissioning]" in fixes
    assert "[DeviceInfo] RevisionNumber='' is not a number; removed" in fixes
    assert "[1001] AccessType='' unknown; assumed ro" in fixes
    assert "[1018] has no ObjectType but sub-indices; set 0x9" in fixes
    assert "[1200sub1] without [1200]; dropped" in fixes
    objects = result.objects
    assert objects[0x1001]["access"] == "ro"
    assert sorted(objects[0x1018]["subs"]) == [0, 1]
    assert 0x1200 not in objects
    assert objects[0x2001]["type"] == "DOMAIN"
    assert "data type 0x000C is not a CiA 301 basic type; read as DOMAIN" in notes
    assert objects[0x2002]["type"] == "REAL32"
    assert "default" not in objects[0x2002]
    assert "min" not in objects[0x2002]
    assert "default '300' does not fit UNSIGNED8" in notes
    assert 0x2004 not in objects
    draft, todos = profile_draft_from_eds(path)
    profile = DeviceProfile.model_validate(draft)
    assert (profile.bus.node_id, profile.bus.bitrate) == (0x20, 250000)
    assert 250000 in profile.bus.bitrates
    assert profile.capabilities.lss
    assert any("LSS needs 1018h sub 1..4" in todo for todo in todos)


def test_import_failure_is_a_value_error(tmp_path, monkeypatch):
    """The loader turns ValueError/OSError from objects_from_eds into a ProfileError."""

    def broken(*_args, **_kwargs):
        raise KeyError(0x1018)

    draft, _ = profile_draft_from_eds(EDS_DIR / "dummy_usage_missing.eds", profile_id="broken-eds")
    del draft["objects"]
    draft["eds"] = "dummy_usage_missing.eds"
    write_profile_draft(draft, tmp_path / "broken-eds.yaml")
    (tmp_path / "dummy_usage_missing.eds").write_bytes((EDS_DIR / "dummy_usage_missing.eds").read_bytes())
    with pytest.raises(OSError):
        objects_from_eds(tmp_path / "missing.eds")
    monkeypatch.setattr(canopen, "import_od", broken)
    with pytest.raises(ValueError, match="canopen cannot read the cleaned EDS: KeyError"):
        objects_from_eds(EDS_DIR / "clean_encoder.eds")
    with pytest.raises(ProfileError, match="eds: cannot import"):
        load_profile(tmp_path / "broken-eds.yaml")


# --------------------------------------------------------------------------- profile drafts


@pytest.mark.parametrize("name", FIXTURES)
def test_draft_validates_after_yaml_round_trip(name, tmp_path):
    profile, todos, text = draft_profile(name, tmp_path)
    assert profile.schema_version == 1
    assert text.startswith(f"# Profile draft {profile.id!r} generated from an EDS")
    assert "# TODO:" in text
    assert todos
    assert "\n  0x1000:\n" in text  # hex object indices
    assert profile.objects.keys() == objects_from_eds(EDS_DIR / name).keys()


def test_draft_of_clean_encoder(tmp_path):
    profile, todos, text = draft_profile("clean_encoder.eds", tmp_path)
    assert profile.id == "clean_encoder"
    identity = profile.identity
    assert (identity.vendor_id, identity.product_code, identity.device_type) == (0xABCDEF, 0x58, 0x00020196)
    assert identity.device_name == "EX58-MT"
    assert identity.revision is not None
    assert identity.revision.min == 0x00010002
    assert profile.bus.bitrates == [1000000, 800000, 500000, 250000, 125000, 50000, 20000, 10000]
    assert profile.bus.node_id_set_by == ["sdo", "lss"]  # 2000h "Node-ID" and LSS_Supported=1
    caps = profile.capabilities
    assert caps.cia406
    assert caps.encoder
    assert caps.multiturn
    assert (caps.tpdos, caps.rpdos) == (2, 0)
    assert caps.heartbeat_producer
    assert not caps.node_guarding
    assert caps.store_subindices == [1, 2]
    assert caps.restore_subindices == [1]
    assert caps.lss
    assert "switch_global" in caps.lss
    assert caps.scaling
    assert caps.preset
    assert caps.speed
    assert not caps.work_area
    assert caps.cam is None
    position = profile.entry(0x6004)
    assert position is not None
    assert position.dynamic
    assert position.default is None
    serial = profile.entry(0x1018, 4)
    assert serial is not None
    assert serial.per_unit
    assert "default: 0x40000181" in text  # COB-IDs in hex
    assert any(todo.startswith("capabilities.encoder_class") for todo in todos)
    assert not any(todo.startswith("EDS repaired") for todo in todos)


def test_draft_capabilities_from_other_fixtures(tmp_path):
    single, _, _ = draft_profile("dummy_usage_missing.eds", tmp_path)
    assert not single.capabilities.multiturn
    assert single.capabilities.node_guarding
    assert not single.capabilities.heartbeat_producer
    assert single.capabilities.lss == []
    assert single.bus.node_id_set_by == ["other"]
    cams, todos, _ = draft_profile("compact_subobj.eds", tmp_path)
    assert cams.capabilities.cam is not None
    assert cams.capabilities.cam.channels == 2
    assert cams.capabilities.heartbeat_consumer_entries == 2
    assert any(todo.startswith("EDS repaired: [6300] CompactSubObj") for todo in todos)
    formulas, todos, _ = draft_profile("nodeid_formulas.eds", tmp_path)
    assert (formulas.capabilities.tpdos, formulas.capabilities.rpdos) == (2, 1)
    assert formulas.capabilities.emcy
    entry = formulas.entry(0x1800, 1)
    assert entry is not None
    assert entry.default == "$NODEID+0x40000180"


def test_draft_id_can_be_given(tmp_path):
    draft, _ = profile_draft_from_eds(EDS_DIR / "odd_formatting.eds", profile_id="example-ex58-odd")
    assert DeviceProfile.model_validate(draft).id == "example-ex58-odd"


def test_profile_with_eds_key_loads(tmp_path):
    """The loader's ``eds:`` merge takes the objects from the EDS; the YAML can override entries."""
    draft, _ = profile_draft_from_eds(EDS_DIR / "clean_encoder.eds", profile_id="eds-merge")
    del draft["objects"]
    draft["eds"] = "clean_encoder.eds"
    draft["objects"] = {0x6004: {"dynamic": True}}
    (tmp_path / "clean_encoder.eds").write_bytes((EDS_DIR / "clean_encoder.eds").read_bytes())
    write_profile_draft(draft, tmp_path / "eds-merge.yaml")
    profile = load_profile(tmp_path / "eds-merge.yaml").profile
    assert profile.objects.keys() == objects_from_eds(EDS_DIR / "clean_encoder.eds").keys()
    position = profile.entry(0x6004)
    assert position is not None
    assert position.dynamic
    assert position.pdo_mappable


# --------------------------------------------------------------------------- export -> import


def assert_round_trip(profile: DeviceProfile, path: Path) -> None:
    export_eds(profile, path)
    result = read_eds(path)
    assert result.fixes == []
    assert signature(result.objects) == profile_signature(profile)
    for index, sub, obj, entry in profile.iter_entries():
        back = entry_of(result.objects, index, sub)
        assert back["name"] == entry.name
        assert back.get("default") == entry.default, f"0x{index:04X}.{sub}"
        allowed = entry.value_set  # an EDS has no value list: its bounds stand in for absent min/max
        low = allowed.minimum if entry.min is None and allowed else entry.min
        high = allowed.maximum if entry.max is None and allowed else entry.max
        assert (back.get("min"), back.get("max")) == (low, high), f"0x{index:04X}.{sub}"
        assert back.get("pdo_mappable", False) == entry.pdo_mappable
        assert (result.objects[index].get("kind") == "array") == (obj.object_kind == "array")


@pytest.mark.parametrize("name", FIXTURES)
def test_draft_export_round_trip(name, tmp_path):
    profile, _, _ = draft_profile(name, tmp_path)
    assert_round_trip(profile, tmp_path / "export.eds")


def test_export_writes_device_info_and_dcf(tmp_path):
    profile, _, _ = draft_profile("nodeid_formulas.eds", tmp_path)
    od = canopen.import_od(str(export_eds(profile, tmp_path / "twin.eds")))
    assert od.device_information.vendor_number == 0xABCDEF
    assert od.device_information.allowed_baudrates == {250000, 500000}
    assert od[0x1800][1].default_raw == "$NODEID+0x40000180"
    dcf = canopen.import_od(str(export_eds(profile, tmp_path / "twin.dcf", node_id=5)))
    assert dcf.node_id == 5
    assert dcf[0x1800][1].value == 0x40000185
    assert "EdsVersion" not in (tmp_path / "twin.eds").read_text(encoding="utf-8")


def _loadable_profiles() -> list[pytest.param]:
    params = []
    for ref in iter_profile_ids():
        marks = [pytest.mark.skip(reason="abstract profile")] if ref.abstract else []
        params.append(pytest.param(ref, id=ref.id, marks=marks))
    return params or [pytest.param(None, id="none", marks=pytest.mark.skip(reason="no device profiles yet"))]


@pytest.mark.parametrize("ref", _loadable_profiles())
def test_device_profile_round_trip(ref, tmp_path):
    try:
        profile = load_profile(ref.path).profile
    except ProfileError as exc:
        pytest.skip(f"profile does not load (being edited?): {exc}")
    assert_round_trip(profile, tmp_path / f"{profile.id}.eds")


STORAGE_EDS = """\
[DeviceInfo]
VendorName=Test
ProductName=Storage groups
[MandatoryObjects]
SupportedObjects=3
1=0x1000
2=0x1001
3=0x1018
[OptionalObjects]
SupportedObjects=4
1=0x1010
2=0x1017
3=0x2000
4=0x2001
[ManufacturerObjects]
SupportedObjects=0
[1000]
ParameterName=Device type
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x00020196
[1001]
ParameterName=Error register
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=0
[1010]
ParameterName=Store parameters
ObjectType=0x8
SubNumber=3
[1010sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=2
[1010sub1]
ParameterName=Save all parameters
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=1
[1010sub2]
ParameterName=Save communication parameters
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=1
[1017]
ParameterName=Producer heartbeat time
ObjectType=0x7
;StorageLocation=PERSIST_COMM
DataType=0x0006
AccessType=rw
DefaultValue=0
[1018]
ParameterName=Identity
ObjectType=0x9
SubNumber=2
[1018sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
[1018sub1]
ParameterName=Vendor-ID
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x1234
[2000]
ParameterName=Scratch value
ObjectType=0x7
;StorageLocation=RAM
DataType=0x0007
AccessType=rw
DefaultValue=0
[2001]
ParameterName=Counter kept by the firmware
ObjectType=0x7
;StorageLocation=PERSIST_TEST
DataType=0x0007
AccessType=rw
DefaultValue=0
"""


def test_storage_location_comments_give_the_storage_groups(tmp_path):
    """`;StorageLocation=` (CANopenEditor's convention): RAM is volatile, PERSIST_COMM stored by 1010h sub 2, a
    firmware's own group is a todo; without the comment the CiA 301 range guess stays (2001h here is guessed)."""
    eds = tmp_path / "storage.eds"
    eds.write_text(STORAGE_EDS, encoding="utf-8")
    draft, todos = profile_draft_from_eds(eds, "storage")
    objects = draft["objects"]
    assert objects[0x1017]["persisted_by"] == "store_comm"
    assert objects[0x2000]["persisted_by"] == "volatile"
    assert any("StorageLocation=PERSIST_TEST (2001h)" in todo for todo in todos)
    assert objects[0x2001]["persisted_by"] == "store_all"  # not named: the CiA 301 group guess, with its todo


def test_a_store_sub_named_for_the_location_wins_over_the_cia_group():
    """CANopenNode's demo EDS: 1010h sub 5 is "Save PERSIST_APP parameters" (CiA's application sub 3 stores
    nothing there): its objects are stored by sub 1, with a todo naming sub 5."""
    eds = Path(__file__).parent / "data" / "eds" / "vendors" / "canopennode-demodevice.eds"
    draft, todos = profile_draft_from_eds(eds)
    assert draft["objects"][0x2111]["subs"][1]["persisted_by"] == "store_all"
    assert draft["objects"][0x1017]["persisted_by"] == "store_comm"
    assert any("1010h sub 5 is named for PERSIST_APP" in todo for todo in todos)
