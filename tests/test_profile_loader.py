"""Profile loading: every shipped profile is valid; malformed ones give one clear ProfileError.

A ProfileError must name the file, the line (where the key exists) and the key path, and say
how to fix it. The bad profiles are written into tmp_path from one small valid profile.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from encoder_conformance.errors import ProfileError
from encoder_conformance.profile.loader import (
    DEFAULT_PROFILE_DIR,
    find_profile,
    iter_profile_ids,
    load_profile,
)
from encoder_conformance.profile.od_builder import build_object_dictionary
from encoder_conformance.profile.schema import (
    SCHEMA_VERSION,
    is_node_id_expression,
    resolve_node_id_expression,
)

REPO = Path(__file__).resolve().parents[1]
PROFILE_REFS = list(iter_profile_ids())

# Line numbers below refer to this text (line 1 = schema_version).
GOOD = """\
schema_version: 1
id: probe
title: Probe encoder
identity: {vendor_name: V, product_name: P, vendor_id: 1, device_type: 0x196, manual: m}
bus: {node_id: 5, bitrate: 250000, bitrates: [250000], node_id_set_by: [fixed], bitrate_set_by: [fixed], manual: m}
capabilities: {cia406: true, heartbeat_producer: true, tpdos: 1}
timing: {bootup_max_ms: 500, sdo_response_max_ms: 50}
objects:
  0x1000: {name: Device type, type: U32, access: const, default: 0x196, manual: m}
  0x1017: {name: Producer heartbeat time, type: U16, access: rw, default: 0, manual: m}
  0x1800:
    name: TPDO1 communication parameter
    manual: m
    subs:
      0: {name: Highest sub-index supported, type: U8, access: const, default: 5}
      1: {name: COB-ID, type: U32, access: rw, default: "$NODEID+0x180"}
"""


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def problems_of(path: Path) -> tuple[ProfileError, str]:
    """Load ``path`` expecting exactly one ProfileError; returns it and its text."""
    with pytest.raises(ProfileError) as info:
        load_profile(path)
    error = info.value
    assert Path(error.path).name == path.name, f"error names {error.path}, not {path}"
    assert path.name in str(error)
    return error, "\n".join(error.problems)


# -- shipped profiles ---------------------------------------------------------------------------


def test_profile_directory_is_not_empty():
    """device_profiles/ holds concrete and abstract profiles."""
    assert any(ref.abstract for ref in PROFILE_REFS)
    assert any(not ref.abstract for ref in PROFILE_REFS)


@pytest.mark.parametrize("ref", PROFILE_REFS, ids=[ref.id for ref in PROFILE_REFS])
def test_shipped_profile_loads(ref):
    """Every profile (abstract ones too) validates; its id is its file name; 'abstract' is not inherited."""
    loaded = load_profile(ref.path)
    assert loaded.profile.id == ref.id
    assert loaded.profile.abstract == ref.abstract
    assert loaded.chain[0] == ref.path.resolve()
    assert len(loaded.sha256) == 64
    assert loaded.profile.iter_entries(), "a profile without objects tests nothing"


def test_load_by_id_finds_the_file():
    """A profile id resolves to device_profiles/<id>.yaml."""
    ref = next(r for r in PROFILE_REFS if not r.abstract)
    assert find_profile(ref.id) == DEFAULT_PROFILE_DIR / f"{ref.id}.yaml"
    assert load_profile(ref.id).profile.id == ref.id


def test_unknown_profile_id_lists_the_known_ones():
    """An unknown id is one ProfileError listing the ids that exist."""
    with pytest.raises(ProfileError) as info:
        load_profile("does-not-exist")
    assert "does-not-exist" in str(info.value)
    assert PROFILE_REFS[0].id in str(info.value)


def test_missing_file_is_a_profile_error(tmp_path):
    """A path to a missing .yaml file is a ProfileError, not an OSError."""
    with pytest.raises(ProfileError, match="no such file"):
        load_profile(tmp_path / "absent.yaml")


def test_good_probe_profile_loads(tmp_path):
    """The base text the malformed cases start from is itself valid."""
    loaded = load_profile(write(tmp_path, "probe.yaml", GOOD))
    assert sorted(loaded.profile.objects) == [0x1000, 0x1017, 0x1800]


# -- malformed profiles -------------------------------------------------------------------------


def test_unknown_key_suggests_the_right_one(tmp_path):
    """An unknown key names file:line, the key path and the closest valid key."""
    path = write(tmp_path, "probe.yaml", GOOD.replace("tpdos: 1}", "tpdos: 1, heartbeat_prodcer: true}"))
    error, text = problems_of(path)
    assert len(error.problems) == 1
    assert text.startswith("probe.yaml:6: capabilities.heartbeat_prodcer: unknown key")
    assert "did you mean 'heartbeat_producer'?" in text


def test_unknown_key_inside_an_object(tmp_path):
    """Key paths inside objects show the index in hex."""
    path = write(tmp_path, "probe.yaml", GOOD.replace("U16, access: rw", "U16, acess: rw"))
    _, text = problems_of(path)
    assert "probe.yaml:10: objects.0x1017.acess: unknown key; did you mean 'access'?" in text


def test_wrong_type(tmp_path):
    """A string where an integer belongs names the key and the expected type (no coercion)."""
    path = write(tmp_path, "probe.yaml", GOOD.replace("tpdos: 1}", 'tpdos: "1"}'))
    _, text = problems_of(path)
    assert "probe.yaml:6: capabilities.tpdos:" in text
    assert "integer" in text


def test_missing_field(tmp_path):
    """A missing required key names its parent's line and says to add it."""
    path = write(tmp_path, "probe.yaml", GOOD.replace("bootup_max_ms: 500, ", ""))
    _, text = problems_of(path)
    assert "probe.yaml:7: timing.bootup_max_ms: required key is missing; add it" in text


def test_missing_top_level_field(tmp_path):
    """A missing top-level key is named (the file is named by the error)."""
    path = write(tmp_path, "probe.yaml", GOOD.replace("title: Probe encoder\n", ""))
    error, text = problems_of(path)
    assert "title: required key is missing" in text
    assert len(error.problems) == 1


def test_several_problems_in_one_error(tmp_path):
    """All validation problems of a file come in one ProfileError, one line each."""
    text = GOOD.replace("tpdos: 1}", "tpdos: -1, heartbeat_prodcer: true}").replace("node_id: 5", "node_id: 200")
    error, joined = problems_of(write(tmp_path, "probe.yaml", text))
    assert len(error.problems) == 3, joined
    assert "bus.node_id" in joined
    assert "capabilities.tpdos" in joined
    assert "capabilities.heartbeat_prodcer" in joined


def test_value_outside_the_type(tmp_path):
    """A default that does not fit its data type names the object."""
    path = write(tmp_path, "probe.yaml", GOOD.replace("U16, access: rw, default: 0", "U16, access: rw, default: 70000"))
    _, text = problems_of(path)
    assert "probe.yaml:10: objects.0x1017:" in text
    assert "70000" in text


@pytest.mark.parametrize(
    "broken",
    ["title: [Probe encoder", "title: Probe: encoder: x"],
    ids=["unclosed-bracket", "mapping-in-scalar"],
)
def test_bad_yaml(tmp_path, broken):
    """YAML syntax errors give line and column, no YAML traceback."""
    path = write(tmp_path, "probe.yaml", GOOD.replace("title: Probe encoder", broken))
    error, text = problems_of(path)
    assert len(error.problems) == 1
    assert re.match(r"line [34], column \d+: not valid YAML: ", text), text


def test_top_level_must_be_a_mapping(tmp_path):
    """A file holding a list (or nothing) is refused with a clear reason."""
    _, text = problems_of(write(tmp_path, "probe.yaml", "- a\n- b\n"))
    assert "mapping" in text
    _, text = problems_of(write(tmp_path, "empty.yaml", ""))
    assert "mapping" in text


def test_unknown_quirk_effect(tmp_path):
    """An unknown quirk effect names the quirk, the bad effect and the known effects."""
    quirk = "quirks:\n  q1: {title: t, manual: m, description: d, effect: sillent_until_bus_traffic}\n"
    _, text = problems_of(write(tmp_path, "probe.yaml", GOOD + quirk))
    assert "probe.yaml:18: quirks.q1.effect:" in text
    assert "unknown quirk effect 'sillent_until_bus_traffic'" in text
    assert "silent_until_bus_traffic" in text.split("known effects:")[1]


@pytest.mark.parametrize("version", ["2", "0", "'1'"])
def test_schema_version_mismatch(tmp_path, version):
    """Another schema_version is refused naming the version found and the version this tool reads."""
    path = write(tmp_path, "probe.yaml", GOOD.replace("schema_version: 1", f"schema_version: {version}"))
    error, text = problems_of(path)
    assert len(error.problems) == 1
    assert "schema_version: is" in text
    assert f"schema_version {SCHEMA_VERSION}" in text


def test_missing_schema_version(tmp_path):
    """A profile without schema_version is refused."""
    _, text = problems_of(write(tmp_path, "probe.yaml", GOOD.replace("schema_version: 1\n", "")))
    assert "schema_version" in text


# -- extends --------------------------------------------------------------------------------------


def parent_and_child(tmp_path: Path, child_body: str, parent_text: str = GOOD) -> Path:
    parent = parent_text.replace("id: probe", "id: parent")
    parent = parent.replace("schema_version: 1\n", "schema_version: 1\nabstract: true\n")
    write(tmp_path, "parent.yaml", parent)
    return write(tmp_path, "child.yaml", "schema_version: 1\nid: child\nextends: parent\ntitle: Child\n" + child_body)


def test_extends_merges_and_drops_abstract(tmp_path):
    """A child inherits everything, overrides single keys, and is not abstract itself."""
    child = parent_and_child(tmp_path, "objects:\n  0x1017: {default: 100}\n")
    loaded = load_profile(child)
    profile = loaded.profile
    assert profile.id == "child"
    assert not profile.abstract
    assert profile.entry(0x1017).default == 100
    assert profile.entry(0x1017).name == "Producer heartbeat time"
    assert [p.name for p in loaded.chain] == ["child.yaml", "parent.yaml"]


@pytest.mark.parametrize("key", ["0x1017", "'1017h'", "'0x1017'"])
def test_null_deletes_an_inherited_object(tmp_path, key):
    """'0x1017: null' (in any index spelling) removes the parent's object; the rest is kept."""
    child = parent_and_child(tmp_path, f"objects:\n  {key}: null\n")
    profile = load_profile(child).profile
    assert 0x1017 not in profile.objects
    assert {0x1000, 0x1800} <= set(profile.objects)


def test_null_default_overrides_instead_of_deleting(tmp_path):
    """'default: null' in a child sets the default to null (it does not delete the entry)."""
    child = parent_and_child(tmp_path, "objects:\n  0x1017: {default: null, dynamic: true}\n")
    entry = load_profile(child).profile.entry(0x1017)
    assert entry is not None
    assert entry.default is None
    assert entry.dynamic


def test_extends_cycle(tmp_path):
    """A circular extends chain is refused naming the chain."""
    write(tmp_path, "cyc-a.yaml", "schema_version: 1\nid: cyc-a\nextends: cyc-b\n")
    write(tmp_path, "cyc-b.yaml", "schema_version: 1\nid: cyc-b\nextends: cyc-a\n")
    _, text = problems_of(tmp_path / "cyc-a.yaml")
    assert "circular" in text
    assert "cyc-a.yaml -> cyc-b.yaml -> cyc-a.yaml" in text


def test_extends_itself(tmp_path):
    """A profile extending itself is a cycle too."""
    _, text = problems_of(write(tmp_path, "self.yaml", "schema_version: 1\nid: self\nextends: self\n"))
    assert "circular" in text


@pytest.mark.parametrize("parent", ["no-such-parent", "no-such-parent.yaml"])
def test_extends_missing_parent(tmp_path, parent):
    """A missing parent (by id or by file name) is named in the error of the child."""
    child = write(tmp_path, "orphan.yaml", f"schema_version: 1\nid: orphan\nextends: {parent}\n")
    _, text = problems_of(child)
    assert text.startswith("orphan.yaml:3: extends:")
    assert "no-such-parent" in text


def test_extends_must_be_a_string(tmp_path):
    """'extends: [a, b]' is refused."""
    _, text = problems_of(write(tmp_path, "probe.yaml", "schema_version: 1\nid: probe\nextends: [a, b]\n"))
    assert text.startswith("extends:")


def test_problem_in_the_parent_names_the_parent_file(tmp_path):
    """A bad key that lives in the parent is reported against the parent file and its line."""
    child = parent_and_child(tmp_path, "", GOOD.replace("tpdos: 1}", "tpdos: 1, heartbeat_prodcer: true}"))
    error, text = problems_of(child)
    assert "parent.yaml:7: capabilities.heartbeat_prodcer: unknown key" in text  # line 7: abstract added
    assert len(error.problems) == 1


def test_problem_in_the_child_names_the_child_file(tmp_path):
    """A bad override in the child is reported against the child file."""
    child = parent_and_child(tmp_path, "capabilities: {tpdos: -1}\n")
    _, text = problems_of(child)
    assert "child.yaml:5: capabilities.tpdos:" in text


def test_bad_yaml_in_the_parent_names_the_parent(tmp_path):
    """A YAML error in a parent file is reported for the parent file."""
    write(tmp_path, "parent.yaml", "schema_version: 1\nid: parent\ntitle: [x\n")
    child = write(tmp_path, "child.yaml", "schema_version: 1\nid: child\nextends: parent\n")
    with pytest.raises(ProfileError) as info:
        load_profile(child)
    assert Path(info.value.path).name == "parent.yaml"
    assert "not valid YAML" in str(info.value)


# -- $NODEID formulas ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("formula", "node_id", "value"),
    [("$NODEID+0x180", 5, 0x185), ("$NODEID + 0x40000180", 127, 0x400001FF), ("0x80+$NODEID", 1, 0x81),
     ("$NODEID+384", 3, 387)],
)
def test_node_id_formula_resolution(formula, node_id, value):
    """'$NODEID+offset' and 'offset+$NODEID' (hex or decimal) resolve for a node-id."""
    assert is_node_id_expression(formula)
    assert resolve_node_id_expression(formula, node_id) == value


def test_non_formulas_pass_through():
    """Numbers, None and ordinary strings are returned unchanged."""
    assert resolve_node_id_expression(0x180, 5) == 0x180
    assert resolve_node_id_expression(None, 5) is None
    assert resolve_node_id_expression("WDGA", 5) == "WDGA"
    assert not is_node_id_expression("$NODE+0x180")


def test_formula_default_in_a_profile(tmp_path):
    """A formula default is kept as text in the profile and resolved per node-id in the OD."""
    profile = load_profile(write(tmp_path, "probe.yaml", GOOD)).profile
    assert profile.entry(0x1800, 1).default == "$NODEID+0x180"
    od = build_object_dictionary(profile, node_id=9)
    assert od[0x1800][1].default == 0x189
    assert od[0x1800][1].default_raw == "$NODEID+0x180"
    assert build_object_dictionary(profile)[0x1800][1].default == 0x185  # profile's delivery node-id


def test_bad_formula_is_refused(tmp_path):
    """A string default on a numeric entry that is not a formula names the entry and the fix."""
    path = write(tmp_path, "probe.yaml", GOOD.replace('"$NODEID+0x180"', '"$NODE+0x180"'))
    _, text = problems_of(path)
    assert "probe.yaml:16: objects.0x1800.subs.1:" in text
    assert "'$NODEID+0x180' formula" in text


# -- command line ----------------------------------------------------------------------------------


def test_cli_validate_reports_problems_without_traceback(tmp_path):
    """'profile validate' prints ok for a good file, the problems of bad ones, exits non-zero, no traceback."""
    good = write(tmp_path, "probe.yaml", GOOD)
    bad = write(tmp_path, "bad.yaml", GOOD.replace("id: probe", "id: bad").replace("tpdos: 1}", "tpdos: 1, tpdo: 2}"))
    broken = write(tmp_path, "broken.yaml", "title: [x\n")
    result = subprocess.run(
        [sys.executable, "-m", "encoder_conformance", "profile", "validate", str(good), str(bad), str(broken),
         str(tmp_path / "absent.yaml")],
        capture_output=True, text=True, timeout=60, cwd=REPO,
    )
    assert result.returncode != 0
    assert "Traceback" not in result.stderr
    assert f"{good}: ok (probe," in result.stdout
    assert "bad.yaml:6: capabilities.tpdo: unknown key; did you mean 'tpdos'?" in result.stderr
    assert "broken.yaml" in result.stderr
    assert "not valid YAML" in result.stderr
    assert "absent.yaml" in result.stderr


# -- regression tests for library bugs found by these tests (fixed) ---------------------------------


def test_non_utf8_file_is_a_profile_error(tmp_path):
    """A Latin-1 encoded profile (umlaut in a title) gives a ProfileError naming the file."""
    path = tmp_path / "probe.yaml"
    path.write_bytes(GOOD.replace("Probe encoder", "Drehgeber für Tests").encode("latin-1"))
    problems_of(path)


def test_hex_suffix_sub_index_keys(tmp_path):
    """Sub-index keys written '10h' / '0Ah' mean hex, like object index keys ('6001h')."""
    text = GOOD.replace("      1: {name: COB-ID", "      '10h': {name: X, type: U8, access: ro, default: 1}\n"
                        "      '0Ah': {name: Y, type: U8, access: ro, default: 1}\n      1: {name: COB-ID")
    profile = load_profile(write(tmp_path, "probe.yaml", text)).profile
    assert sorted(profile.objects[0x1800].subs) == [0, 1, 0x0A, 0x10]


@pytest.mark.parametrize(
    ("replace", "line"),
    [(("schema_version: 1", "schema_version: 2"), 1), (("title: Probe encoder", "extends: nope.yaml\ntitle: x"), 3)],
    ids=["schema_version", "extends"],
)
def test_non_schema_problems_name_the_line(tmp_path, replace, line):
    """Every problem reads 'file:line: key.path: ...', also for schema_version and extends."""
    _, text = problems_of(write(tmp_path, "probe.yaml", GOOD.replace(*replace)))
    assert text.startswith(f"probe.yaml:{line}: ")


def test_id_must_equal_the_file_name(tmp_path):
    """A profile whose id differs from its file name is refused."""
    _, text = problems_of(write(tmp_path, "other-name.yaml", GOOD))
    assert "id" in text


def test_duplicate_keys_are_refused(tmp_path):
    """An object index given twice is an error naming the key, not a silent override."""
    dup = GOOD + "  0x1017: {name: Again, type: U8, access: ro, manual: m}\n"
    _, text = problems_of(write(tmp_path, "probe.yaml", dup))
    assert "0x1017" in text or "duplicate" in text


def test_misspelled_quirk_parameter(tmp_path):
    """A misspelled parameter of a quirk effect names file, line, the key path and the likely key."""
    quirk = ("quirks:\n  q1:\n    title: t\n    manual: m\n    description: d\n    effect: writes_preop_only\n"
             "    params:\n      objects: [0x2100]\n      abort_cod: 0x08000022\n")
    _, text = problems_of(write(tmp_path, "probe.yaml", GOOD + quirk))
    assert "probe.yaml:25: quirks.q1.params.abort_cod: unknown key; did you mean 'abort_code'?" in text


def test_ill_typed_quirk_parameter(tmp_path):
    """A parameter of the wrong type names file, line and key path."""
    quirk = ("quirks:\n  q1:\n    title: t\n    manual: m\n    description: d\n    effect: abort_code\n"
             "    params: {situation: value_high, codes: [high]}\n")
    _, text = problems_of(write(tmp_path, "probe.yaml", GOOD + quirk))
    assert "probe.yaml:23: quirks.q1.params.codes.0:" in text


def test_quirk_without_effect_keeps_free_params(tmp_path):
    """A documentation-only quirk may carry any params (values for a proposed effect)."""
    quirk = "quirks:\n  q1: {title: t, manual: m, description: d, params: {anything: [1, 2]}}\n"
    profile = load_profile(write(tmp_path, "probe.yaml", GOOD + quirk)).profile
    assert profile.quirks["q1"].params == {"anything": [1, 2]}


def test_effect_table_in_profile_readme_is_current():
    """device_profiles/README.md shows the effect table generated from the parameter models."""
    from encoder_conformance.profile.quirks import effect_table

    readme = (REPO / "device_profiles" / "README.md").read_text(encoding="utf-8")
    assert effect_table() in readme, (
        "device_profiles/README.md's effect table is out of date: replace it with the output of "
        "`encoder-conformance profile effects`"
    )


def test_a_profile_loaded_again_is_the_loaded_one_until_a_file_of_its_chain_changes(tmp_path):
    """A second load (the run's forked twin loads the run's profile) takes the one loaded, as named this time;
    an edited file, its own or one it extends, is read again."""
    parent = write(tmp_path, "probe.yaml", GOOD)
    child = write(tmp_path, "probe-child.yaml", "schema_version: 1\nid: probe-child\nextends: probe\n")
    first = load_profile(child)
    again = load_profile(str(child))
    assert again.profile is first.profile
    assert again.path == Path(str(child))
    parent.write_text(GOOD.replace("title: Probe encoder", "title: Probe encoder, edited"), encoding="utf-8")
    edited = load_profile(child)
    assert edited.profile is not first.profile
    assert edited.profile.title == "Probe encoder, edited"
