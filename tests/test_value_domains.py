"""Declared value domains: ValueSet parsing and probes, profile validation, declared_domain, the twin."""

from __future__ import annotations

from pathlib import Path

import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError
from pydantic import ValidationError

from encoder_conformance.dut.store.changeable import changeable_parameter, other_valid_value
from encoder_conformance.errors import ProfileError
from encoder_conformance.profile.eds import export_eds
from encoder_conformance.profile.loader import deep_merge, load_profile
from encoder_conformance.profile.schema import EntrySpec, ObjectSpec
from encoder_conformance.profile.value_domain import declared_domain, probe_values
from encoder_conformance.profile.value_set import ValueSet
from tests import sim_rig
from tests.sim_rig import MINIMAL

rig = sim_rig.rig  # the shared fixture

VALUE_INVALID, VALUE_HIGH, VALUE_LOW = 0x06090030, 0x06090031, 0x06090032


# -- ValueSet ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "ranges"),
    [
        ("0..4, 6..9", ((0, 4), (6, 9))),
        ("0, 10..65535", ((0, 0), (10, 65535))),
        ("0x10..0x20", ((16, 32),)),
        ("0X1f, 7", ((7, 7), (31, 31))),
        ("-5..-1, 3", ((-5, -1), (3, 3))),
        ("8, 2, 0", ((0, 0), (2, 2), (8, 8))),
        ("0..5, 3..8, 9", ((0, 9),)),  # overlapping and adjacent ranges merge
        ("007", ((7, 7),)),
        (" 1 .. 3 ", ((1, 3),)),
    ],
)
def test_parse(text, ranges):
    assert ValueSet.parse(text).ranges == ranges


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("0..x", "allowed '0..x': 'x' is not an integer"),
        ("1.5", "allowed '1.5': '1.5' is not an integer"),
        ("0..4,,6", "allowed '0..4,,6': empty item between commas"),
        ("", "allowed '': write a text of integers"),
        ("9..4", "allowed '9..4': range '9..4' is empty"),
        ("1..2..3", "allowed '1..2..3': '2..3' is not an integer"),
        ("0x", "allowed '0x': '0x' is not an integer"),
    ],
)
def test_parse_errors_name_the_text(text, message):
    with pytest.raises(ValueError, match="^" + message.replace(".", r"\.")):
        ValueSet.parse(text)


def test_parse_refuses_a_number():
    with pytest.raises(ValueError, match="allowed 7: write a text"):
        ValueSet.parse(7)  # type: ignore[arg-type]


def test_contains_and_bounds():
    values = ValueSet.parse("0..4, 6..9")
    assert [v for v in range(-1, 12) if v in values] == [0, 1, 2, 3, 4, 6, 7, 8, 9]
    assert "5" not in values
    assert (values.minimum, values.maximum) == (0, 9)
    assert str(values) == "0..4, 6..9"
    assert ValueSet(()).minimum is None
    assert not ValueSet(())


def test_intersection_and_outside():
    values = ValueSet.parse("0..4, 6..9")
    assert values & ValueSet.span(3, 7) == ValueSet.parse("3, 4, 6, 7")
    assert (values & ValueSet.span(20, 30)).ranges == ()
    assert ValueSet.span(0, 10).outside(values) == ValueSet.parse("5, 10")
    assert ValueSet.parse("3..4").issubset(values)
    assert not ValueSet.parse("4..6").issubset(values)


@pytest.mark.parametrize(
    ("text", "low", "high", "probes"),
    [
        ("0..4, 6..9", 0, 255, [5, 10]),  # one probe for the one-value gap
        ("0, 10..65535", 0, 65535, [1, 9]),  # nothing above the type's top
        ("1..240, 255", 0, 255, [0, 241, 254]),
        ("0..255", 0, 255, []),  # the whole type range: nothing to probe
        ("-8388608..8388607", -(1 << 31), (1 << 31) - 1, [-8388609, 8388608]),
        ("0, 2, 8", 0, 0xFFFFFFFF, [1, 3, 7, 9]),
    ],
)
def test_probes(text, low, high, probes):
    values = ValueSet.parse(text)
    assert values.probes(low, high) == probes
    assert not any(p in values for p in probes)


# -- profile validation --------------------------------------------------------------------------


def entry(**fields):
    return EntrySpec(**{"name": "x", "type": "U8", "access": "rw", **fields})


def test_entry_keeps_the_text_and_parses_it():
    spec = entry(min=0, max=9, allowed="0..4, 6..9", default=9)
    assert spec.allowed == "0..4, 6..9"
    assert spec.value_set == ValueSet.parse("0..4, 6..9")
    assert entry().value_set is None


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"allowed": "0..x"}, "allowed '0..x': 'x' is not an integer"),
        ({"allowed": "0..300"}, "allowed '0..300' goes outside UNSIGNED8 (0..255)"),
        ({"allowed": "-1..3"}, "allowed '-1..3' goes outside UNSIGNED8"),
        ({"allowed": "0..4, 6..9", "max": 8}, "allowed '0..4, 6..9' holds 9, above max 8"),
        ({"allowed": "0..4", "min": 1}, "allowed '0..4' holds 0, below min 1"),
        ({"allowed": "0..4, 6..9", "default": 5}, "default 5 is not in allowed '0..4, 6..9'"),
        ({"allowed": "0..4", "type": "REAL32"}, "only integer types have allowed values"),
        ({"allowed": "1", "type": "VISIBLE_STRING"}, "only integer types have allowed values"),
        ({"allowed": 5}, "allowed 5: write a text"),
    ],
)
def test_entry_refuses_inconsistent_allowed(fields, message):
    with pytest.raises(ValidationError, match=message.replace("(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        entry(**fields)


def test_var_object_passes_allowed_to_its_entry():
    obj = ObjectSpec(name="NMT startup", manual="m", type="U32", access="rw", default=0, allowed="0, 2, 8")
    assert obj.entries()[0].allowed == "0, 2, 8"
    with pytest.raises(ValidationError, match="default 1 is not in allowed"):
        ObjectSpec(name="NMT startup", manual="m", type="U32", access="rw", default=1, allowed="0, 2, 8")


def test_record_object_refuses_allowed_on_the_object():
    with pytest.raises(ValidationError, match="allowed belong"):
        ObjectSpec(name="r", manual="m", allowed="0..1", subs={0: entry()})


def test_null_allowed_in_a_child_clears_it():
    merged = deep_merge({"allowed": "0..4", "name": "x"}, {"allowed": None})
    assert merged == {"allowed": None, "name": "x"}


# -- declared_domain on the shipped profiles ----------------------------------------------------


def profile(name: str):
    return load_profile(name).profile


def test_declared_domain_takes_allowed():
    faulhaber = profile("faulhaber-mc5005")
    assert declared_domain(faulhaber, 0x2400, 1) == ValueSet.parse("0..4, 6..9")
    assert probe_values(faulhaber, 0x2400, 1) == [5, 10]
    siko = profile("siko-wx58m-1212-mt")
    assert declared_domain(siko, 0x1017, 0) == ValueSet.parse("0, 10..65535")
    assert probe_values(siko, 0x1017, 0) == [1, 9]


def test_declared_domain_takes_min_max_and_type_range():
    waycon = profile("waycon-sx")
    assert declared_domain(waycon, 0x2101, 0) == ValueSet.span(1, 127)
    assert probe_values(waycon, 0x2101, 0) == [0, 128]
    wdga = profile("wachendorff-wdga-mt")
    assert declared_domain(wdga, 0x1017, 0) == ValueSet.span(0, 0xFFFF)
    assert probe_values(wdga, 0x1017, 0) == []


def test_declared_domain_takes_tpdo_transmission_types():
    waycon = profile("waycon-sx")
    assert declared_domain(waycon, 0x1800, 2) == ValueSet.parse("1..240, 255")
    assert probe_values(waycon, 0x1800, 2) == [0, 241, 254]
    assert declared_domain(waycon, 0x1800, 5) == ValueSet.span(0, 0xFFFF)  # other subs: no TPDO types


def test_declared_domain_none_for_other_types_and_absent_entries():
    wdga = profile("wachendorff-wdga-mt")
    assert wdga.entry(0x1008, 0).type == "VISIBLE_STRING"
    assert declared_domain(wdga, 0x1008, 0) is None
    assert probe_values(wdga, 0x1008, 0) == []
    assert declared_domain(wdga, 0x1234, 0) is None


# -- loader and EDS export -----------------------------------------------------------------------


def minimal_with_domains(tmp_path: Path) -> Path:
    """The minimal encoder with 1017h allowed '0, 10..65535' and a U8 2001h min 1 max 9 allowed '1..4, 6..9'."""
    text = MINIMAL.read_text(encoding="utf-8").replace("id: minimal-encoder", "id: domains")
    old_1017 = "0x1017: {name: Producer heartbeat time, type: U16, access: rw, default: 0,"
    assert old_1017 in text
    text = text.replace(old_1017, old_1017 + ' allowed: "0, 10..65535",')
    text = text.replace(
        "  0x6000:",
        '  0x2001: {name: Mode, type: U8, access: rw, default: 1, allowed: "1..4, 6..9", min: 1, max: 9,'
        " manual: fixture}\n"
        '  0x2002: {name: Filter, type: U8, access: rw, default: 3, allowed: "0x02..0x04", manual: fixture}\n'
        "  0x6000:",
    )
    path = tmp_path / "domains.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_loader_reports_a_bad_allowed_with_file_and_line(tmp_path):
    path = minimal_with_domains(tmp_path)
    path.write_text(path.read_text(encoding="utf-8").replace('"1..4, 6..9"', '"1..4, 6..y"'), encoding="utf-8")
    with pytest.raises(ProfileError) as info:
        load_profile(path)
    text = str(info.value)
    assert "domains.yaml" in text
    assert "objects.0x2001.allowed" in text
    assert "allowed '1..4, 6..y': 'y' is not an integer" in text


def test_eds_export_writes_the_bounds_of_allowed(tmp_path):
    loaded = load_profile(minimal_with_domains(tmp_path)).profile
    od = canopen.import_od(str(export_eds(loaded, tmp_path / "domains.eds")))
    assert (od[0x2002].min, od[0x2002].max) == (2, 4)  # no min/max: the set's bounds
    assert (od[0x2001].min, od[0x2001].max) == (1, 9)  # min/max given: kept


# -- the twin refuses values outside the domain ----------------------------------------------------


def abort_code(client: canopen.RemoteNode, index: int, sub: int, data: bytes) -> int:
    with pytest.raises(SdoAbortedError) as info:
        client.sdo.download(index, sub, data)
    return int(info.value.code)


def test_twin_refuses_values_outside_the_domain(rig, tmp_path):
    loaded = load_profile(minimal_with_domains(tmp_path)).profile
    _, client = rig.boot(loaded)
    assert abort_code(client, 0x2001, 0, bytes([5])) == VALUE_INVALID  # the gap
    assert abort_code(client, 0x2001, 0, bytes([10])) == VALUE_HIGH
    assert abort_code(client, 0x2001, 0, bytes([0])) == VALUE_LOW
    assert client.sdo.upload(0x2001, 0) == bytes([1])
    assert abort_code(client, 0x1017, 0, (9).to_bytes(2, "little")) == VALUE_INVALID
    assert abort_code(client, 0x1800, 2, bytes([241])) == VALUE_INVALID  # CiA: 241..251 reserved
    client.sdo.download(0x2001, 0, bytes([6]))
    client.sdo.download(0x1017, 0, (10).to_bytes(2, "little"))
    assert client.sdo.upload(0x2001, 0) == bytes([6])


def test_fault_value_domain_ignored_accepts_them(rig, tmp_path):
    loaded = load_profile(minimal_with_domains(tmp_path)).profile
    _, client = rig.boot(loaded, faults=("value_domain_ignored",))
    client.sdo.download(0x2001, 0, bytes([5]))
    client.sdo.download(0x6001, 0, (5000).to_bytes(4, "little"))  # above the plain max too
    assert client.sdo.upload(0x2001, 0) == bytes([5])


# -- parameter pickers stay inside the domain ------------------------------------------------------


def test_parameter_pickers_skip_values_outside_the_domain():
    faulhaber = profile("faulhaber-mc5005")
    assert other_valid_value(faulhaber, 0x2400, 1, 4) == 3  # 5 is not a Tab. 19 index
    assert other_valid_value(faulhaber, 0x2400, 1, 6) == 7
    wdga = profile("wachendorff-wdga-mt")
    assert changeable_parameter(wdga, lambda index, e: index == 0x1F80) is None  # 0 -> 1 is not allowed
