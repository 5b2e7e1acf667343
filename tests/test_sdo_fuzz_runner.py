"""The SDO fuzz runner and device watch against an in-process twin: fault-free examples pass, each fault of
sim/sdo_fuzz_faults.py is reported, and an NMT state change, a restart or an EMCY during an example is noticed."""

from __future__ import annotations

import pytest

from encoder_conformance.dut.device import DeviceUnderTest
from encoder_conformance.fuzz import strategies as fz
from encoder_conformance.fuzz.runner import FuzzRunner
from encoder_conformance.fuzz.watch import DeviceWatch
from encoder_conformance.profile.loader import load_profile
from tests import sim_rig
from tests.sim_rig import MINIMAL, Rig

rig = sim_rig.rig  # the shared fixture
HEARTBEAT_MS = 20
UPLOAD_1000 = fz.Request(bytes.fromhex("40 00 10 00 00 00 00 00"))
ABSENT_WRITE = fz.Request(bytes.fromhex("23 00 F0 00 01 02 03 04"), refused=True)  # F000h: reserved area
SEGMENTED_UPLOAD_1008 = fz.Request(bytes.fromhex("40 08 10 00 00 00 00 00"))
SHORT = fz.Request(bytes.fromhex("40 00 10"))
RESERVED = fz.Request(bytes.fromhex("E0 00 10 00 00 00 00 00"))


def _runner(rig: Rig, faults: tuple[str, ...] = ()) -> tuple[FuzzRunner, object]:
    profile = load_profile(str(MINIMAL)).profile
    node, client = rig.boot(profile, faults=faults)
    client.sdo.download(0x1017, 0, HEARTBEAT_MS.to_bytes(2, "little"))
    dut = DeviceUnderTest(rig.network, rig.log, profile, node.node_id)
    watch = DeviceWatch(dut, HEARTBEAT_MS, 0x80 + node.node_id)
    assert watch.begin() is None
    return FuzzRunner(dut, watch), node


def test_fault_free_examples_pass(rig):
    runner, _ = _runner(rig)
    for example in [(UPLOAD_1000,), (ABSENT_WRITE,), (SHORT,), (RESERVED,), (SEGMENTED_UPLOAD_1008, UPLOAD_1000)]:
        assert runner.run(example) == [], example
    assert runner.final_check() == []
    assert runner.exchanges >= 10


@pytest.mark.parametrize(("fault", "example", "words"), [
    ("dead_after_short_frame", (SHORT,), "no reply"),
    ("double_abort", (ABSENT_WRITE,), "2 replies"),
    ("answers_short_frame_with_garbage", (SHORT,), "shorter than 8 bytes is answered"),
    ("answers_client_abort", (UPLOAD_1000,), "abort transfer request"),
    ("crashes_on_interleaved_initiate", (fz.Request(bytes.fromhex("21 00 F0 00 09 00 00 00")), UPLOAD_1000),
     "no reply"),
])
def test_each_fault_is_reported(rig, fault, example, words):
    runner, _ = _runner(rig, (fault,))
    problems = runner.run(example)
    assert any(words in p for p in problems), problems
    assert runner.failure is not None


def test_an_emcy_is_kept_as_a_warning(rig):
    runner, _ = _runner(rig, ("emcy_on_unknown_command",))
    assert runner.run((RESERVED,)) == []
    assert runner.first_emcy is not None
    assert runner.first_emcy.requests[0] == RESERVED
    assert len(runner.watch.emcy) == 1


def test_another_nmt_state_is_noticed(rig):
    runner, node = _runner(rig)
    rig.nmt(0x01, node.node_id)  # start: operational, SDO still served
    assert runner.dut.wait_heartbeat(rig.log.mark(), 1.0, state=0x05) is not None
    assert any("NMT state 05h" in p for p in runner.run((UPLOAD_1000,)))


def test_a_restart_is_noticed(rig):
    runner, node = _runner(rig)
    mark = rig.log.mark()
    node.reboot(0.001)
    assert rig.wait_bootup(node.node_id, mark) is not None
    runner.dut.responds()
    problems = runner.watch.problems()
    assert any("restarted" in p for p in problems), problems
