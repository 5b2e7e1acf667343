"""``profile from-eds X.eds --probe``: the live probe corrects a draft and leaves the device as found (issue 28).

Against the twins of the shipped profiles (their EDS exported by ``to-eds``, so the EDS holds only what an EDS
can): the probed draft has the profile's checkable capabilities, except for the differences listed below with
their reasons (each a point the probe does not ask, or a twin that does more than its manual documents).
"""

from __future__ import annotations

import re
import uuid
from pathlib import Path
from typing import Any

import pytest

from encoder_conformance.cli.main import main as cli_main
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.probe.apply import apply_findings
from encoder_conformance.probe.findings import Findings
from encoder_conformance.probe.link import Answer
from encoder_conformance.probe.put_back import PutBack
from encoder_conformance.probe.session import ProbeOptions, ProbeResult, probe_device
from encoder_conformance.profile.eds import export_eds, profile_draft_from_eds, write_profile_draft
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.node import SimulatedNode
from tests.sim_rig import Twin, twin_of

SHIPPED = ["wachendorff-wdga-mt", "faulhaber-mc5005", "fraba-posital-awc58-c2-mt", "siko-wx58m-1212-mt", "waycon-sx",
           "cia406-c3-st"]
#: capabilities compared (as sets where they are lists)
CHECKABLE = ("heartbeat_producer", "heartbeat_consumer_entries", "node_guarding", "emcy", "sync_consumer",
             "sync_producer", "segmented_sdo", "block_sdo", "store_subindices", "restore_subindices", "tpdos", "rpdos",
             "tpdo_transmission_types", "lss")
NOT_PROBED_LSS = "LSS services the probe does not ask (they change the device or need an unconfigured one)"
EXPLAINED: dict[str, dict[str, str]] = {
    "wachendorff-wdga-mt": {
        "lss": NOT_PROBED_LSS + ": configure_bit_timing, store_configuration",
        "node_guarding": "guarding unanswered by the twin; the EDS has 100Ch, so the draft keeps its guess and a todo",
    },
    "faulhaber-mc5005": {"lss": NOT_PROBED_LSS + ": configure_bit_timing"},
    "fraba-posital-awc58-c2-mt": {
        "segmented_sdo": "the manual documents expedited transfer only; the twin's SDO server takes segmented too",
        "tpdo_transmission_types": "the manual's sync counter takes 1..255 (UMD-CA §4.2.3), CiA's reserved 241..251 "
                                   "included: the probe names them a deviation and keeps CiA's list (issue 40)",
    },
    "siko-wx58m-1212-mt": {
        "segmented_sdo": "the manual documents expedited transfer only; the twin's SDO server takes segmented too",
        "tpdo_transmission_types": "18xxh sub 2 is read-only (fixed FEh): the probe gives [254], the profile keeps "
                                   "the CiA list, which no test uses for a read-only type",
    },
    "waycon-sx": {
        "segmented_sdo": "the manual documents expedited transfer only; the twin's SDO server takes segmented too",
    },
    "cia406-c3-st": {
        "lss": NOT_PROBED_LSS + ": configure_bit_timing, activate_bit_timing, store_configuration, "
                      "identify_non_configured, fastscan",
        "sync_producer": "the class profile says 'may' (either reading); a probe sees one",
    },
}


def probed(eds: Path, twin: Twin, node_id: int, **options: Any) -> tuple[dict[str, Any], ProbeResult]:
    draft, todos = profile_draft_from_eds(eds)
    result = probe_device(draft, todos, ProbeOptions(twin.bus, node_id, boot_timeout_s=6.0, **options))
    return draft, result


def loaded(draft: dict[str, Any], todos: list[str], folder: Path) -> DeviceProfile:
    out = folder / f"{draft['id']}.yaml"
    write_profile_draft(draft, out, todos)
    return load_profile(out).profile


def _comparable(value: Any) -> Any:
    return sorted(value) if isinstance(value, list) else value


def _state(node: SimulatedNode, profile: DeviceProfile) -> dict[tuple[int, int], bytes]:
    """Every non-dynamic entry's value as the twin would send it."""
    return {(index, sub): node.encode_current((index, sub)) for index, sub, _, entry in profile.iter_entries()
            if not (entry.dynamic or entry.per_unit) and entry.access != "wo"}


@pytest.mark.parametrize("profile_id", SHIPPED)
def test_probe_of_a_shipped_twin_reproduces_its_checkable_capabilities(profile_id: str, tmp_path: Path):
    shipped = load_profile(profile_id).profile
    eds = export_eds(shipped, tmp_path / f"{profile_id}.eds", shipped.bus.node_id)
    with twin_of(shipped) as twin:
        before, stored_before = _state(twin.node, shipped), twin.node.nvm.snapshot()
        values_before = {key: twin.node.current_value(key) for key in before}
        draft, result = probed(eds, twin, shipped.bus.node_id)
        after, stored_after = _state(twin.node, shipped), twin.node.nvm.snapshot()
    assert result.restored
    assert before == after, "the probe leaves every value as found"
    # what the twin boots with is unchanged: a device that stores every write (SIKO) stores the value it had
    assert {key: value for key, value in stored_after.items()
            if stored_before.get(key, values_before.get(key)) != value} == {}
    assert stored_before.keys() <= stored_after.keys()
    profile = loaded(draft, result.todos, tmp_path)
    differences = {name for name in CHECKABLE
                   if _comparable(getattr(profile.capabilities, name)) != _comparable(getattr(shipped.capabilities,
                                                                                              name))}
    assert differences == set(EXPLAINED[profile_id]), {
        name: (getattr(profile.capabilities, name), getattr(shipped.capabilities, name)) for name in differences}
    assert set(profile.objects) == set(shipped.objects)
    assert profile.bus.node_id == shipped.bus.node_id
    for field in ("vendor_id", "product_code", "device_type"):
        shown = getattr(shipped.identity, field)
        assert shown is None or getattr(profile.identity, field) == shown


def _eds_with_extra_object(eds: Path, index: int) -> None:
    text = eds.read_text(encoding="utf-8")
    count = int(re.search(r"\[OptionalObjects\]\s*SupportedObjects=(\d+)", text).group(1))  # type: ignore[union-attr]
    text = text.replace(f"[OptionalObjects]\nSupportedObjects={count}",
                        f"[OptionalObjects]\nSupportedObjects={count + 1}\n{count + 1}=0x{index:04X}", 1)
    text += (f"\n[{index:04X}]\nParameterName=Not in the device\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\n"
             "DefaultValue=0\nPDOMapping=0\n")
    eds.write_text(text, encoding="utf-8")


def test_an_object_the_device_lacks_is_removed_with_a_todo(tmp_path: Path):
    shipped = load_profile("cia406-c3-st").profile
    eds = export_eds(shipped, tmp_path / "extra.eds", shipped.bus.node_id)
    _eds_with_extra_object(eds, 0x2345)
    with twin_of(shipped) as twin:
        draft, result = probed(eds, twin, shipped.bus.node_id, reset=False)
    assert 0x2345 not in draft["objects"]
    warning = [todo for todo in result.todos if "2345h" in todo and "removed" in todo]
    assert len(warning) == 1
    assert warning[0].startswith("warning: ")
    assert "CiA 306" in warning[0]
    assert "EDS extra.eds [2345]" in warning[0]
    assert "upload 2345h.00 -> abort 06020000h" in warning[0]


def test_a_value_that_changes_across_a_reset_is_no_default():
    """CANopenNode's power-on counter (2106h): read-only, one more after every reset."""
    draft: dict[str, Any] = {"bus": {"node_id": 4}, "identity": {}, "capabilities": {},
                             "objects": {0x2106: {"name": "Power-on counter", "type": "U32", "access": "ro",
                                                  "default": 0}}}
    findings = Findings(reset=True)
    findings.readings[0x2106, 0] = [Answer(b"\x07\0\0\0"), Answer(b"\x07\0\0\0"), Answer(b"\x08\0\0\0")]
    todos = apply_findings(draft, [], findings, 4)
    entry = draft["objects"][0x2106]
    assert entry["dynamic"] is True
    assert "default" not in entry
    assert any("2106h" in todo and "reset" in todo for todo in todos)


class _DeafLink:
    """A device that takes writes without keeping them (the put-back check must say so)."""

    def __init__(self) -> None:
        self.value = b"\x05\x00"

    def read(self, index: int, sub: int) -> Answer:
        return Answer(self.value)

    def write(self, index: int, sub: int, data: bytes, force_segment: bool = False) -> Answer:
        if data != b"\x05\x00":
            self.value = data  # the probe's change sticks, the put-back does not
        return Answer(b"")


def test_put_back_says_which_entry_did_not_come_back():
    link = _DeafLink()
    ledger = PutBack(link)  # type: ignore[arg-type]  # why: a stand-in with the two methods PutBack uses
    assert ledger.write(0x1017, 0, b"\x64\x00").ok
    failures = ledger.restore()
    assert len(failures) == 1
    assert failures[0].startswith("1017h sub 0: found 05 00, now 64 00")


def test_cli_probe_writes_the_corrected_draft(tmp_path: Path, capsys, monkeypatch):
    shipped = load_profile("waycon-sx").profile
    eds = export_eds(shipped, tmp_path / "waycon.eds", shipped.bus.node_id)
    monkeypatch.chdir(tmp_path)
    with twin_of(shipped) as twin:
        status = cli_main(["profile", "from-eds", str(eds), "-o", "probed.yaml", "--probe", "--can-interface",
                           "virtual", "--can-channel", twin.bus.kwargs["channel"], "--node-id",
                           str(shipped.bus.node_id)])
    out = capsys.readouterr().out
    assert status == RunExit.PASSED, out
    assert "every value written was put back and read back" in out
    assert load_profile(tmp_path / "probed.yaml").profile.bus.node_id == shipped.bus.node_id


def test_cli_probe_of_a_silent_node_writes_nothing(tmp_path: Path, capsys, monkeypatch):
    shipped = load_profile("waycon-sx").profile
    eds = export_eds(shipped, tmp_path / "waycon.eds", shipped.bus.node_id)
    monkeypatch.chdir(tmp_path)
    status = cli_main(["profile", "from-eds", str(eds), "-o", "probed.yaml", "--probe", "--can-interface", "virtual",
                       "--can-channel", f"nobody-{uuid.uuid4().hex[:6]}", "--node-id", "5"])
    assert status == RunExit.COULD_NOT_TEST
    assert "did not answer an SDO read of 1000h" in capsys.readouterr().err
    assert not (tmp_path / "probed.yaml").exists()


