"""The probe's profile is right the first time (issue 40): an entry that answers 08000024h is present without data
(``no_data``), never readable; a reserved transmission type the device takes is a finding, never a capability; the
EDS's inconsistencies and what the device contradicts in it are warnings naming CiA 306 and the EDS line; every
finding names the frames it rests on. End to end against the twin variant ``empty_arrays`` and the twin fault
``reserved_transmission_types_accepted``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from encoder_conformance.cli.main import main as cli_main
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.plugin.selection import ENTRY_FIXTURES
from encoder_conformance.probe.apply import apply_findings
from encoder_conformance.probe.findings import Findings, TpdoTypes
from encoder_conformance.probe.link import Answer
from encoder_conformance.probe.services import store_restore_subindices
from encoder_conformance.profile.eds import profile_draft_from_eds
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.schema import EntrySpec
from encoder_conformance.profile.value_domain import refusal_basis
from tests.sim_rig import twin_of
from tests.suite_session import run_suite
from tests.test_eds_corpus import _draft_file, _probed_draft_file
from tests.test_probe import probed as probed_against

EDS = Path(__file__).parent / "data" / "eds" / "inconsistent_arrays.eds"
NO_DATA = 0x08000024


def _array_draft() -> dict[str, Any]:
    """A draft with one ARRAY whose sub 0 has no default (as from an EDS without one) and the error history."""
    subs = {0: {"name": "Number of entries", "type": "U8", "access": "ro", "manual": "EDS x.eds [2100sub0]"},
            **{n: {"name": f"Data {n}", "type": "U32", "access": "rw", "default": 0,
                   "manual": f"EDS x.eds [2100sub{n}]"} for n in (1, 2)}}
    history = {0: {"name": "Number of errors", "type": "U8", "access": "rw", "dynamic": True},
               1: {"name": "Error 1", "type": "U32", "access": "ro", "dynamic": True}}
    return {"bus": {"node_id": 4}, "identity": {}, "capabilities": {},
            "objects": {0x2100: {"name": "Customer data", "kind": "array", "subs": subs},
                        0x1003: {"name": "Error history", "kind": "array", "subs": history}}}


def test_an_entry_without_data_is_never_readable():
    entry = EntrySpec(name="Data 1", type="U32", access="rw", no_data=True)
    assert (entry.readable, entry.writable, entry.checks_default) == (False, False, False)
    assert not any(ENTRY_FIXTURES[name](entry) for name in ("readable_entry", "read_only_entry", "default_entry"))
    read_only = EntrySpec(name="Record 1", type="U32", access="ro", no_data=True)
    assert not ENTRY_FIXTURES["read_only_entry"](read_only), "test_read_only_entry_refuses_write reads it first"
    with pytest.raises(ValidationError, match="no_data"):
        EntrySpec(name="Data 1", type="U32", access="rw", default=0, no_data=True)


def test_08000024h_is_recorded_as_no_data_with_the_count_from_sub_0_and_its_frames():
    draft = _array_draft()
    findings = Findings()
    findings.readings[0x2100, 0] = [Answer(b"\x00")]
    findings.readings[0x2100, 1] = [Answer(abort=NO_DATA)]
    findings.readings[0x2100, 2] = [Answer(abort=NO_DATA)]
    findings.readings[0x1003, 0] = [Answer(b"\x00")]
    findings.readings[0x1003, 1] = [Answer(abort=NO_DATA)]  # an empty error history entry: fills at run time
    draft["objects"][0x2100]["subs"][2].update(dynamic=True, default=None)  # a run-time value (e.g. 6030h speed)
    todos = apply_findings(draft, [], findings, 4)
    subs = draft["objects"][0x2100]["subs"]
    assert subs[2]["no_data"] is True, "a run-time value without data is no_data too (kacanopen's 6030h)"
    assert subs[1]["no_data"] is True
    assert "default" not in subs[1]
    assert subs[0]["default"] == 0, "the count is taken from sub 0 where the EDS gives none"
    assert "no_data" not in draft["objects"][0x1003]["subs"][1]
    found = [todo for todo in todos if "2100h" in todo]
    assert len(found) == 1
    assert "upload 2100h.01 -> abort 08000024h" in found[0]
    assert "upload 2100h.00 -> 00" in found[0]


def test_a_reserved_transmission_type_taken_is_a_finding_never_a_capability():
    draft: dict[str, Any] = {"bus": {"node_id": 4}, "identity": {}, "capabilities": {}, "objects": {}}
    frames = {t: f"download 1800h.02 {t:02X} -> accepted" for t in range(256)}
    findings = Findings(tpdo_types=TpdoTypes(0x1800, list(range(256)), {}, frames))
    todos = apply_findings(draft, [], findings, 4)
    assert draft["capabilities"]["tpdo_transmission_types"] == [*range(241), 252, 253, 254, 255]
    deviation = [todo for todo in todos if "DEVIATION" in todo]
    assert len(deviation) == 1
    assert "241..251" in deviation[0]
    assert "download 1800h.02 F1 -> accepted" in deviation[0]
    assert "CiA 301 §7.5.2.37" in deviation[0]


def test_a_reserved_transmission_type_rests_on_cia_whatever_the_profile_lists():
    profile = load_profile("wachendorff-wdga-mt").profile  # its list leaves out 241..253 on the manual's word
    assert refusal_basis(profile, 0x1800, 2, 241)[0] == "cia"
    assert refusal_basis(profile, 0x1800, 2, 253)[0] == profile.capabilities.tpdo_transmission_types_refusal


def test_what_the_device_contradicts_in_the_eds_is_a_warning_naming_cia_306_and_the_section():
    draft = _array_draft()
    draft["objects"][0x2100]["subs"][2]["access"] = "ro"
    findings = Findings()
    findings.readings[0x2100, 0] = [Answer(b"\x02")]
    findings.readings[0x2100, 1] = [Answer(b"\x01\x00")]  # U32 in the EDS, 2 bytes on the wire
    findings.readings[0x2100, 2] = [Answer(abort=0x06010001)]  # refused as a write-only entry
    warnings = [todo for todo in apply_findings(draft, [], findings, 4) if todo.startswith("warning: ")]
    assert len(warnings) == 2
    assert all("CiA 306" in w and "EDS x.eds [2100sub" in w for w in warnings)
    assert "upload 2100h.01 -> 01 00" in warnings[0]
    assert "upload 2100h.02 -> abort 06010001h" in warnings[1]


def test_the_eds_inconsistencies_are_warnings_with_their_lines(tmp_path: Path, capsys, monkeypatch):
    _, todos = profile_draft_from_eds(EDS)
    warnings = [todo for todo in todos if todo.startswith("warning: ")]
    assert any("[OptionalObjects] line 122" in w and "SupportedObjects=13 but 14" in w and "CiA 306" in w
               for w in warnings)
    assert any("2100h [2100sub0] line 388" in w and "2101h [2101sub0] line 432" in w and "CiA 306" in w
               for w in warnings)
    monkeypatch.chdir(tmp_path)
    assert cli_main(["profile", "from-eds", str(EDS), "-o", "drafted.yaml"]) == RunExit.PASSED
    err = capsys.readouterr().err
    assert err.count("WARNING") == 2
    assert "SupportedObjects=13" in err
    kept = load_profile(tmp_path / "drafted.yaml").profile.todo
    assert any("SupportedObjects=13" in todo for todo in kept), "the warnings are kept in the draft"


@pytest.fixture(scope="module")
def drafts(tmp_path_factory) -> tuple[Path, Path]:
    """The plain draft of inconsistent_arrays.eds (the twin plays it) and the draft the probe corrects against
    its twin with empty ARRAYs (the variant of the stack that loaded the EDS)."""
    folder = tmp_path_factory.mktemp("no-data")
    plain = _draft_file(EDS, folder)
    return plain, _probed_draft_file(EDS, plain, folder)


def test_the_twin_variant_holds_no_element_and_the_probed_profile_says_so(drafts):
    plain, probed = drafts
    profile = load_profile(probed).profile
    assert [s for s, e in profile.objects[0x2100].entries().items() if e.no_data] == [1, 2, 3, 4]
    assert profile.entry(0x2101, 0).default == 0
    with twin_of(load_profile(plain).profile, faults=("empty_arrays",)) as twin:
        _, result = probed_against(EDS, twin, profile.bus.node_id, reset=False)
    assert any("upload 2101h.01 -> abort 08000024h" in todo for todo in result.todos)


def test_probed_profile_passes_against_the_twin_variant_where_the_eds_draft_fails(drafts, tmp_path: Path):
    """The suites that picked such entries as readable (issue 40: 100 failures) pass with the probed profile."""
    plain, probed = drafts
    chosen = "test_object_dictionary or test_sdo_protocol or test_sdo_block"
    passed, _ = run_suite(tmp_path / "probed", "--ec-profile", str(probed), "--ec-sim-profile", str(plain),
                          "--ec-sim-fault", "empty_arrays", "-k", chosen)
    assert passed.returncode == 0, passed.output[-3000:]
    unprobed, _ = run_suite(tmp_path / "plain", "--ec-profile", str(plain), "--ec-sim-fault", "empty_arrays",
                            "-k", "test_readable_entry_exists_with_declared_size")
    assert unprobed.returncode == 1
    assert "2100h.01 declared readable but the read aborted" in unprobed.output


def test_a_twin_accepting_reserved_types_probed_then_run_fails_naming_1800h_sub_2(drafts, tmp_path: Path,
                                                                                     capsys, monkeypatch):
    plain, _ = drafts
    shipped = load_profile(plain).profile
    monkeypatch.chdir(tmp_path)
    with twin_of(shipped, faults=("reserved_transmission_types_accepted",)) as twin:
        status = cli_main(["profile", "from-eds", str(EDS), "-o", "probed.yaml", "--probe", "--no-reset",
                           "--can-interface", "virtual", "--can-channel", twin.bus.kwargs["channel"],
                           "--node-id", str(shipped.bus.node_id)])
    assert status == RunExit.PASSED
    assert "DEVIATION: 1800h sub 2 accepted the transmission types CiA reserves: 241..251" in capsys.readouterr().out
    probed = load_profile(tmp_path / "probed.yaml").profile
    assert not set(probed.capabilities.tpdo_transmission_types) & set(range(241, 252))
    run, _ = run_suite(tmp_path, "--ec-profile", str(tmp_path / "probed.yaml"), "--ec-sim-profile", str(plain),
                       "--ec-sim-fault", "reserved_transmission_types_accepted", "-k", "test_value_domain and 0x1800")
    assert run.returncode == 1, run.output[-3000:]
    assert "1800h.02 Transmission type" in run.output
    assert "write of 241 (0xF1)" in run.output


def test_store_commands_without_data_are_no_capability():
    """1010h with sub 0 = 0 (its elements answer 08000024h): the device stores on no command."""
    draft: dict[str, Any] = {"bus": {"node_id": 4}, "identity": {}, "capabilities": {"store_subindices": [1]},
                             "objects": {0x1010: {"name": "Store parameters", "kind": "array", "subs": {
                                 0: {"name": "Count", "type": "U8", "access": "ro"},
                                 1: {"name": "Save all", "type": "U32", "access": "rw", "default": 1}}}}}
    findings = Findings()
    findings.readings[0x1010, 0] = [Answer(b"\x00")]
    findings.readings[0x1010, 1] = [Answer(abort=NO_DATA)]
    store_restore_subindices(findings)
    apply_findings(draft, [], findings, 4)
    assert draft["capabilities"]["store_subindices"] == []
    assert draft["objects"][0x1010]["subs"][1]["no_data"] is True
