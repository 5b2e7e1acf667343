"""The state before the judgement (issue 39): the one way into an NMT state sees it by the heartbeat, a check for a
kept error sends no SDO to a stopped device, and each reset ends in the state the device documents.

Twin level (``sim_rig``): the variants and the fault behave as declared, and the DUT layer reads no SDO in stopped.
Suite level (one targeted session each): the reset-state test catches a self-starting device, naming the state
it observed, and nothing else fails but what depends on the reset state; a documented self-starting device passes;
a start refused in stopped with a kept error is not testable, never failed.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from encoder_conformance.cia.cia301 import SDO_REQUEST_BASE, NmtCommand
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.dut.nmt.persistent_error import persisting_error
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.runs.fault_matrix import run_suite
from encoder_conformance.sim.engine.nmt import NmtState
from tests import sim_rig
from tests.sim_rig import Rig

rig = sim_rig.rig  # the shared simulator fixture
PROFILE = "wachendorff-wdga-mt"
#: what a device that starts itself after every reset may legitimately fail: the checks of the state a reset ends in
DEPENDS_ON_RESET_STATE = {"test_state_after_reset", "test_autostart_object_starts_device_after_reset",
                          "test_nmt_sequences_follow_the_cia301_model"}


class _Notes:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def note(self, text: str) -> None:
        self.lines.append(text)


def _dut(rig: Rig, faults: tuple[str, ...] = ()) -> tuple[DeviceUnderTest, object]:
    profile = load_profile(PROFILE).profile
    node, _ = rig.boot(profile, faults=faults)
    return DeviceUnderTest(rig.network, rig.log, profile, node.node_id), node


def test_self_starts_after_reset_enters_operational_after_every_boot_up(rig):
    dut, node = _dut(rig, ("self_starts_after_reset",))
    assert node.state is NmtState.OPERATIONAL
    for command in (NmtCommand.RESET_NODE, NmtCommand.RESET_COMMUNICATION):
        mark = rig.nmt(command, node.node_id)
        assert rig.wait_bootup(node.node_id, mark) is not None
        dut.read(0x1000)  # the host takes frames in order: the boot-up's hooks ran before this answer
        assert node.state is NmtState.OPERATIONAL


def test_a_documented_self_starting_device_starts_with_its_autostart_value(rig):
    dut, node = _dut(rig, ("autostart_set_at_delivery",))
    assert dut.read_uint(0x1F80) == 0x08
    assert node.state is NmtState.OPERATIONAL


def test_the_check_for_a_kept_error_sends_no_sdo_to_a_stopped_device(rig):
    """The stays-stopped variant refuses NMT start in stopped; persisting_error brings it out of stopped (enter
    pre-operational, 7Fh seen) before its first SDO request, and finds the kept error."""
    dut, node = _dut(rig, ("device_error_at_start_stays_stopped",))
    journal, notes = SettingsJournal(dut), _Notes()
    dut.nmt.transition("stopped", journal, notes)
    stopped = rig.nmt(NmtCommand.START, node.node_id)
    assert rig.log.wait_for(lambda m: dut.is_heartbeat(m) and bytes(m.data) == b"\x04", sim_rig.WAIT_S, stopped)
    assert node.state is NmtState.STOPPED
    assert persisting_error(dut) == 0x01
    sent = rig.log.since(stopped)
    first_sdo = next(n for n, m in enumerate(sent)
                     if not m.is_rx and m.arbitration_id == SDO_REQUEST_BASE + dut.node_id)
    left = [m for m in sent[:first_sdo] if dut.is_heartbeat(m) and bytes(m.data) in (b"\x7f", b"\x00")]
    assert left, "an SDO request went to the device before a heartbeat showed it out of stopped"
    journal.restore()


def test_a_state_not_reached_names_the_state_the_heartbeat_reports(rig):
    dut, _node = _dut(rig, ("ignore_enter_preop",))
    journal, notes = SettingsJournal(dut), _Notes()
    dut.nmt.transition("operational", journal, notes)
    with pytest.raises(AssertionError, match=r"the heartbeat reports 05h \(operational\), not 7Fh \(pre-operational\)"):
        dut.nmt.transition("pre-operational", journal, notes)
    journal.restore()


def _failures(folder: Path) -> dict[str, str]:
    """test name -> message of every failed test of the run in ``folder``."""
    summary = json.loads((folder / "run-summary.json").read_text(encoding="utf-8"))
    return {r["nodeid"].split("::")[1]: r.get("message") or "" for r in summary["results"]
            if r["outcome"] in ("failed", "error")}


def test_the_reset_state_test_catches_a_self_starting_device(tmp_path):
    result = run_suite(PROFILE, "self_starts_after_reset", tmp_path, targeted=True)
    failed = _failures(tmp_path / "self_starts_after_reset")
    resets = {f"test_state_after_reset[{r}]" for r in ("reset-node", "reset-communication", "power-on")}
    assert resets <= set(failed)
    assert {name.split("[")[0] for name in failed} <= DEPENDS_ON_RESET_STATE, sorted(failed)
    for name in resets:
        assert "the device is in 05h (operational)" in failed[name], failed[name]
    assert result.returncode == 1


def test_a_documented_self_starting_device_passes_the_reset_state_test(tmp_path):
    result = run_suite(PROFILE, "autostart_set_at_delivery", tmp_path, targeted=True, select="test_nmt.py")
    assert _failures(tmp_path / "autostart_set_at_delivery") == {}
    assert result.outcomes["test_nmt::test_state_after_reset[reset-node]"] == "passed"
    assert result.returncode == 0


def test_a_start_refused_in_stopped_with_a_kept_error_is_not_testable(tmp_path):
    fault = "device_error_at_start_stays_stopped"
    result = run_suite(PROFILE, fault, tmp_path, targeted=True, select="test_transition")
    assert _failures(tmp_path / fault) == {}
    assert result.outcomes["test_nmt::test_transition[stopped --start--> 05h]"] == "skipped"
