"""The device's faces (issue 41): ``dut.nmt`` reaches every state from every state by ``transition`` and sees it
there, its commands are the only NMT frames, ``dut.tpdo[n]`` names its parameters and frames, ``dut.lss`` reads the
LSS address, and a package's face imports its names on first use and knows no others."""

from __future__ import annotations

import can
import pytest

import encoder_conformance.dut.nmt as nmt_face
from encoder_conformance.cia.cia301 import NMT_COB_ID, TPDO1_BASE, NmtCommand
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.sim.engine.nmt import NmtState
from tests import sim_rig
from tests.sim_rig import Rig

rig = sim_rig.rig  # the shared simulator fixture
PROFILE = "wachendorff-wdga-mt"
REACHED = {"pre-operational": NmtState.PRE_OPERATIONAL, "operational": NmtState.OPERATIONAL,
           "stopped": NmtState.STOPPED}


class _Notes:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def note(self, text: str) -> None:
        self.lines.append(text)


def _dut(rig: Rig) -> tuple[DeviceUnderTest, object]:
    profile = load_profile(PROFILE).profile
    node, _ = rig.boot(profile)
    return DeviceUnderTest(rig.network, rig.log, profile, node.node_id), node


def test_transition_reaches_every_state_from_every_state_and_puts_the_heartbeat_back(rig):
    dut, node = _dut(rig)
    journal = dut.custody.journal()
    heartbeat = dut.read_uint(0x1017)
    for start in REACHED:
        for target in REACHED:
            dut.nmt.transition(start, journal, _Notes())
            assert node.state is REACHED[start]
            dut.nmt.transition(target, journal, _Notes())
            assert node.state is REACHED[target], f"{start} -> {target}"
    dut.nmt.transition("pre-operational", journal, _Notes())
    assert journal.restore() == []
    assert dut.read_uint(0x1017) == heartbeat


def test_transition_names_the_states_it_knows(rig):
    dut, _ = _dut(rig)
    with pytest.raises(ValueError, match="pre-operational, operational, stopped"):
        dut.nmt.transition("sleeping", dut.custody.journal(), _Notes())


def test_a_command_is_one_nmt_frame_to_the_device_or_the_node_given(rig):
    dut, node = _dut(rig)
    mark = dut.nmt.command("stop")
    dut.nmt.command("pre-operational", node_id=0)
    sent = [bytes(m.data) for m in dut.frames.since(mark, lambda m: not m.is_rx and m.arbitration_id == NMT_COB_ID)]
    assert sent == [bytes([NmtCommand.STOP, node.node_id]), bytes([NmtCommand.ENTER_PRE_OPERATIONAL, 0])]
    assert dut.nmt.reset_node() is not None
    assert node.state is NmtState.PRE_OPERATIONAL


def test_a_tpdo_knows_its_parameters_and_frames(rig):
    dut, node = _dut(rig)
    first, fourth = dut.tpdo[1], dut.tpdo.at(0x1803)
    assert (first.comm, first.mapping_index, fourth.number) == (0x1800, 0x1A00, 4)
    assert first.can_id() == TPDO1_BASE + node.node_id
    frames = first.frames()
    assert frames(_frame(TPDO1_BASE + node.node_id))
    assert not frames(_frame(TPDO1_BASE + node.node_id, rx=False))
    assert not frames(_frame(TPDO1_BASE + node.node_id, remote=True))
    assert first.silence_s == dut.pdo_silence_s
    assert first.answer_s >= 0.3
    for number in (0, 513):
        with pytest.raises(IndexError):
            dut.tpdo[number]


def test_the_lss_address_is_the_identity_object(rig):
    dut, _ = _dut(rig)
    address = dut.lss.address()
    assert address.parts() == tuple(dut.read_uint(0x1018, sub) for sub in range(1, 5))


def test_a_face_imports_its_names_on_first_use_and_knows_no_others():
    assert nmt_face.NmtFace.__name__ == "NmtFace"
    with pytest.raises(AttributeError, match="has no attribute 'nothing'"):
        _ = nmt_face.nothing


def _frame(can_id: int, rx: bool = True, remote: bool = False) -> can.Message:
    return can.Message(arbitration_id=can_id, is_extended_id=False, is_rx=rx, is_remote_frame=remote,
                       data=b"" if remote else b"\x01\x02")
