"""The twin's conformant variants of the SYNC, error-behaviour and PDO open readings (encoder_conformance/open_points/):
each plays the reading it names, and the default twin the other one."""

from __future__ import annotations

from pathlib import Path

import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import EmcyCode
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.sim.engine.sync_producer import FIRST_SYNC_LATE_S
from tests import sim_rig
from tests.sim_rig import WAIT_S, Rig

FULL_PDO = load_profile(str(Path(__file__).parent / "data" / "profiles" / "cia406-full-pdo.yaml")).profile
GENERIC = load_profile("cia406-c3-st").profile  # capabilities.sync_producer: may
NODE = FULL_PDO.bus.node_id
START, PRE_OP = 0x01, 0x80
rig = sim_rig.rig  # the shared simulator fixture


def _u32(value: int) -> bytes:
    return value.to_bytes(4, "little")


def _heartbeat_state(rig: Rig, mark) -> int | None:
    beat = rig.log.wait_for(lambda m: m.is_rx and m.arbitration_id == 0x700 + NODE and m.data and m.data[0] != 0,
                            WAIT_S, mark)
    return None if beat is None else beat.data[0]


def test_sync_producer_sends_sync_every_1006h(rig: Rig):
    _, sdo = rig.boot(FULL_PDO)  # capabilities.sync_producer: true
    sdo.sdo.download(0x1005, 0, _u32(0x40000080))
    mark = rig.log.mark()
    sdo.sdo.download(0x1006, 0, _u32(5000))
    syncs = rig.log.wait_count(lambda m: m.is_rx and m.arbitration_id == 0x080, 3, WAIT_S, mark)
    assert len(syncs) == 3
    sdo.sdo.download(0x1006, 0, _u32(0))
    stopped = rig.log.mark()
    assert rig.scheduler_drained(0.02)
    assert rig.log.since(stopped, lambda m: m.is_rx and m.arbitration_id == 0x080) == []


def test_the_sync_producer_variant_sends_its_first_sync_late_as_canopennode(rig: Rig):
    """The variant's first SYNC comes FIRST_SYNC_LATE_S after the 1006h write (CANopenNode's demo: 49 ms at 10 ms),
    then every 1006h: the suite's producer test waits an answer window for it (no silence window)."""
    _, sdo = rig.boot(FULL_PDO, faults=("sync_producer",))
    sdo.sdo.download(0x1005, 0, _u32(0x40000080))
    mark = rig.log.mark()
    sdo.sdo.download(0x1006, 0, _u32(10000))
    written = rig.log.since(mark)[-1].timestamp  # the write's confirmation
    syncs = rig.log.wait_count(lambda m: m.is_rx and m.arbitration_id == 0x080, 3, WAIT_S, mark)
    sdo.sdo.download(0x1006, 0, _u32(0))
    assert len(syncs) == 3
    assert syncs[0].timestamp - written >= FIRST_SYNC_LATE_S - 0.01
    assert syncs[2].timestamp - syncs[0].timestamp < FIRST_SYNC_LATE_S


def test_default_twin_of_a_may_profile_refuses_the_generate_bit(rig: Rig):
    _, sdo = rig.boot(GENERIC)
    with pytest.raises(SdoAbortedError) as refused:
        sdo.sdo.download(0x1005, 0, _u32(0x40000080))
    assert refused.value.code == 0x06090030


def test_sync_timeout_variant_holds_the_node_in_preoperational_until_reset(rig: Rig):
    _, sdo = rig.boot(FULL_PDO, faults=("sync_timeout_error",))
    sdo.sdo.download(0x1017, 0, (10).to_bytes(2, "little"))
    mark = rig.log.mark()
    sdo.sdo.download(0x1006, 0, _u32(10000))
    emcy = rig.log.wait_for(lambda m: m.is_rx and m.arbitration_id == 0x80 + NODE, WAIT_S, mark)
    assert emcy is not None
    assert int.from_bytes(emcy.data[:2], "little") == EmcyCode.COMMUNICATION
    sdo.sdo.download(0x1006, 0, _u32(0))
    assert _heartbeat_state(rig, rig.nmt(START, NODE)) == 0x7F  # the error is still active: no operational
    boot = rig.nmt(0x82, NODE)
    assert rig.wait_bootup(NODE, boot) is not None
    assert int.from_bytes(sdo.sdo.upload(0x1001, 0), "little") == 0
    sdo.sdo.download(0x1017, 0, (10).to_bytes(2, "little"))
    assert _heartbeat_state(rig, rig.nmt(START, NODE)) == 0x05


def test_pdo_config_variant_refuses_in_operational_only(rig: Rig):
    _, sdo = rig.boot(FULL_PDO, faults=("pdo_config_refused_in_operational",))
    cob_id = int.from_bytes(sdo.sdo.upload(0x1800, 1), "little")
    rig.nmt(START, NODE)
    assert rig.scheduler_drained(0.01)
    with pytest.raises(SdoAbortedError) as refused:
        sdo.sdo.download(0x1800, 1, _u32(cob_id | 0x80000000))
    assert refused.value.code == 0x08000022
    rig.nmt(PRE_OP, NODE)
    assert rig.scheduler_drained(0.01)
    sdo.sdo.download(0x1800, 1, _u32(cob_id | 0x80000000))
