"""A device that keeps an error across resets and stays out of operational (open reading
persistent-error-holds-pre-operational): the twin's variant, and the DUT layer that makes such a device's tests
not testable instead of failed, while an error a reset clears leaves the verdict standing."""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import EMCY_BASE, ERROR_REGISTER, EmcyCode, NmtCommand
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.dut.nmt.persistent_error import kept_error, persisting_error
from encoder_conformance.dut.tpdo.periodic_capture import PeriodicCapture
from encoder_conformance.errors import HeldByPersistentError
from encoder_conformance.plugin.outcomes import is_device_finding
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.sim.engine.nmt import NmtState
from tests import sim_rig
from tests.sim_rig import Rig

rig = sim_rig.rig  # the shared simulator fixture
VARIANT = "device_error_at_start"


class _Notes:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def note(self, text: str) -> None:
        self.lines.append(text)

    def deviation(self, quirk_id: str, text: str) -> None:
        self.lines.append(f"{quirk_id}: {text}")


def _dut(rig: Rig, faults: tuple[str, ...] = ()) -> tuple[DeviceUnderTest, object]:
    profile = load_profile("wachendorff-wdga-mt").profile
    node, _ = rig.boot(profile, faults=faults)
    return DeviceUnderTest(rig.network, rig.log, profile, node.node_id), node


def _emcy_code(rig: Rig, node_id: int, after) -> int | None:
    frame = rig.frame(EMCY_BASE + node_id, after)
    return None if frame is None else int.from_bytes(bytes(frame.data[:2]), "little")


def _resets_sent(rig: Rig, node_id: int, after) -> int:
    return len([m for m in rig.log.since(after) if not m.is_rx and m.arbitration_id == 0
                and bytes(m.data) == bytes([NmtCommand.RESET_COMMUNICATION, node_id])])


def test_the_variant_fails_at_every_start_and_keeps_the_failure(rig):
    """EMCY 5000h with 1001h = 01h after each boot-up (reset communication too); NMT start leaves it in
    pre-operational; another error going away keeps the failure in 1001h and in the error reset EMCY."""
    profile = load_profile("wachendorff-wdga-mt").profile
    mark = rig.log.mark()
    node, sdo = rig.boot(profile, faults=(VARIANT,))
    assert _emcy_code(rig, node.node_id, mark) == EmcyCode.DEVICE_HARDWARE
    assert sdo.sdo.upload(ERROR_REGISTER, 0) == b"\x01"
    rig.nmt(NmtCommand.START, node.node_id)
    sdo.sdo.upload(ERROR_REGISTER, 0)  # the host takes frames in order: the NMT start was handled before it
    assert node.state is NmtState.PRE_OPERATIONAL
    mark = rig.nmt(NmtCommand.RESET_COMMUNICATION, node.node_id)
    assert rig.wait_bootup(node.node_id, mark) is not None
    assert _emcy_code(rig, node.node_id, mark) == EmcyCode.DEVICE_HARDWARE
    mark = rig.log.mark()
    node.clear_emcy()
    reset = rig.frame(EMCY_BASE + node.node_id, mark)
    assert reset is not None
    assert bytes(reset.data[:3]) == b"\x00\x00\x01"
    assert sdo.sdo.upload(ERROR_REGISTER, 0) == b"\x01"


def test_an_error_kept_after_a_reset_makes_operational_not_testable_resetting_once(rig):
    """start_operational on the variant: a skip naming 1001h and the failure's 1003h entry, not a verdict; the second
    test that needs operational costs no second reset (a device that boots in seconds would pay it in every test)."""
    dut, _node = _dut(rig, (VARIANT,))
    journal, notes = SettingsJournal(dut), _Notes()
    mark = rig.log.mark()
    for _ in range(2):
        held_by = r"not testable: NMT start \(to enter operational\): .*1001h = 01h.*00005000h"
        with pytest.raises(HeldByPersistentError, match=held_by) as held:
            dut.nmt.transition("operational", journal, notes)
        assert not is_device_finding(held.value)
    assert _resets_sent(rig, dut.node_id, mark) == 1
    assert kept_error(dut) == 0x01
    journal.restore()


def test_an_error_a_reset_clears_leaves_the_verdict_to_the_test(rig):
    """An error a test left (a heartbeat consumer time-out) is cleared by reset communication: no reason to skip."""
    dut, node = _dut(rig)
    node.raise_emcy(EmcyCode.HEARTBEAT, 0x10)
    assert dut.read_uint(ERROR_REGISTER) & 0x10  # (the WDGA sets no bit 0 with it: a documented quirk)
    assert persisting_error(dut) is None
    assert dut.read_uint(ERROR_REGISTER) == 0
    assert kept_error(dut) == 0


def test_the_periodic_capture_does_not_count_a_tpdo_stream_a_kept_error_holds_back(rig):
    """The heartbeat stream is captured in pre-operational; the event-timer TPDO stream, which needs operational,
    is not testable (a skip reason), not a failure."""
    dut, _node = _dut(rig, (VARIANT,))
    capture = PeriodicCapture.at_test_period(dut, 3)
    capture.take(dut, None)
    assert capture.kept_error == 0x01
    assert capture.event_timer.error is None
    assert capture.event_timer.skip is not None
    assert capture.event_timer.skip.startswith("not testable: the event-timer TPDO stream")
    assert capture.heartbeat.error is None
    assert len(capture.heartbeat.timestamps) == 3
