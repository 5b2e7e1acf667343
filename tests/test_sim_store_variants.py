"""Twin behaviour of the FAULHABER and WayCon store variants and the guarding/heartbeat exclusivity.

Quirks ``reload_immediate`` (FAULHABER 1010h.04/.05 sets, 1011h.04-06 at once),
``manufacturer_store_object`` (WayCon 2105h) and ``guarding_heartbeat_exclusive`` (FAULHABER).
"""

from __future__ import annotations

import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.quirk_effects import ReloadImmediate
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.store_variants import ParameterSets, set_slot
from tests import sim_rig

rig = sim_rig.rig  # the shared fixture

SAVE = (0x65766173).to_bytes(4, "little")
LOAD = (0x64616F6C).to_bytes(4, "little")
KV = (0x2348, 1)


def _fast(profile_id: str) -> DeviceProfile:
    profile = load_profile(profile_id).profile
    return profile.model_copy(update={"simulator": profile.simulator.model_copy(update={"bootup_delay_ms": 5})})


def _u(client: canopen.RemoteNode, index: int, sub: int = 0) -> int:
    return int.from_bytes(client.sdo.upload(index, sub), "little")


def _reset_node(rig, node_id: int) -> None:
    assert rig.wait_bootup(node_id, rig.nmt(0x81, node_id)) is not None, "no boot-up after reset node"


@pytest.fixture(scope="module")
def faulhaber() -> DeviceProfile:
    return _fast("faulhaber-mc5005")


def test_parameter_sets_from_params():
    sets = ParameterSets.from_params(ReloadImmediate.model_validate({"reload_immediate": {4: 3, 5: 4}, "app_sets": {
        "saved_by": {4: 1}, "objects": ["0x2348.1", "0x2344"]}}))
    assert sets.reloads == {4: 3, 5: 4}
    assert sets.saves_set == {4: 1}
    assert sets.set_objects == ((0x2348, 1), (0x2344, 0))
    assert sets.handles((0x1010, 4))
    assert sets.handles((0x1011, 5))
    assert not sets.handles((0x1010, 1))
    assert not sets.handles((0x1011, 1))
    assert set_slot(2, (0x2348, 1)) == (0x22348, 1)


def test_faulhaber_sets_switch_at_once_and_survive_power_cycle(rig, faulhaber):
    """Save Kv as set 1 and set 2, then 1011h.05/.06 switch between them without a reset."""
    node, client = rig.boot(faulhaber)
    client.sdo.download(*KV, bytes([10]))
    client.sdo.download(0x1010, 4, SAVE)  # set 1: Kv 10
    client.sdo.download(*KV, bytes([20]))
    client.sdo.download(0x1010, 5, SAVE)  # set 2: Kv 20
    client.sdo.download(0x1011, 5, LOAD)
    assert _u(client, *KV) == 10
    client.sdo.download(0x1011, 6, LOAD)
    assert _u(client, *KV) == 20
    mark = rig.log.mark()
    node.power_cycle()
    rig.send(0x80)  # the MC waits for bus traffic to detect the bit rate (quirk autobaud-delivery-state)
    assert rig.wait_bootup(node.node_id, mark) is not None
    client.sdo.download(0x1011, 5, LOAD)
    assert _u(client, *KV) == 10, "a set survives a power cycle"


def test_faulhaber_reload_user_parameters_at_once(rig, faulhaber):
    """1011h.04 brings back what 1010h.03 saved, at once; a restore sub 1-3 still waits for the reset."""
    node, client = rig.boot(faulhaber)
    client.sdo.download(*KV, bytes([30]))
    client.sdo.download(0x1010, 3, SAVE)
    client.sdo.download(*KV, bytes([31]))
    client.sdo.download(0x1011, 4, LOAD)
    assert _u(client, *KV) == 30
    client.sdo.download(0x1011, 3, LOAD)
    assert _u(client, *KV) == 30, "restore factory application parameters waits for the reset"
    _reset_node(rig, node.node_id)
    assert _u(client, *KV) == 1, "factory value (the lowest valid, no default given) after restore + reset"


def test_faulhaber_reload_refuses_wrong_signature(rig, faulhaber):
    _, client = rig.boot(faulhaber)
    with pytest.raises(SdoAbortedError) as info:
        client.sdo.download(0x1011, 5, SAVE)
    assert info.value.code == 0x08000020


def test_faulhaber_reload_not_immediate_fault(rig, faulhaber):
    _, client = rig.boot(faulhaber, faults=("reload_not_immediate",))
    client.sdo.download(*KV, bytes([10]))
    client.sdo.download(0x1010, 4, SAVE)
    client.sdo.download(*KV, bytes([20]))
    client.sdo.download(0x1011, 5, LOAD)
    assert _u(client, *KV) == 20


def test_faulhaber_heartbeat_producer_clears_guard_time(rig, faulhaber):
    _, client = rig.boot(faulhaber)
    client.sdo.download(0x100C, 0, (100).to_bytes(2, "little"))
    client.sdo.download(0x1017, 0, (50).to_bytes(2, "little"))
    assert _u(client, 0x100C) == 0
    with pytest.raises(SdoAbortedError) as info:
        client.sdo.download(0x100C, 0, (100).to_bytes(2, "little"))
    assert info.value.code == 0x08000020
    client.sdo.download(0x100C, 0, (0).to_bytes(2, "little"))  # 0 stays allowed (decided, see the quirk)
    client.sdo.download(0x1017, 0, (0).to_bytes(2, "little"))
    client.sdo.download(0x100C, 0, (100).to_bytes(2, "little"))
    assert _u(client, 0x100C) == 100


def test_faulhaber_guarding_coexist_fault(rig, faulhaber):
    _, client = rig.boot(faulhaber, faults=("guarding_heartbeat_coexist",))
    client.sdo.download(0x100C, 0, (100).to_bytes(2, "little"))
    client.sdo.download(0x1017, 0, (50).to_bytes(2, "little"))
    assert _u(client, 0x100C) == 100


@pytest.fixture(scope="module")
def waycon() -> DeviceProfile:
    return _fast("waycon-sx")


def test_waycon_2105h_saves_manufacturer_objects_only(rig, waycon):
    """2104h kept over reset node only after 2105h 'save'; 1010h does not save it."""
    node, client = rig.boot(waycon)
    client.sdo.download(0x2104, 0, b"\x01")
    client.sdo.download(0x1010, 1, SAVE)
    _reset_node(rig, node.node_id)
    assert _u(client, 0x2104) == 0, "1010h does not store 2104h (quirk store-1010-communication-only)"
    client.sdo.download(0x2104, 0, b"\x01")
    client.sdo.download(0x2105, 0, SAVE)
    _reset_node(rig, node.node_id)
    assert _u(client, 0x2104) == 1
    with pytest.raises(SdoAbortedError):
        client.sdo.download(0x2105, 0, LOAD)


def test_waycon_node_id_moves_after_2105h_save_and_reset(rig, waycon):
    node, client = rig.boot(waycon)
    client.sdo.download(0x2101, 0, b"\x09")
    client.sdo.download(0x2105, 0, SAVE)
    mark = rig.nmt(0x81, 7)
    assert rig.wait_bootup(9, mark) is not None, "boot-up on the new node-id 9"
    assert node.node_id == 9


def test_waycon_manufacturer_store_fault(rig, waycon):
    node, client = rig.boot(waycon, faults=("manufacturer_store_not_persisted",))
    client.sdo.download(0x2104, 0, b"\x01")
    client.sdo.download(0x2105, 0, SAVE)
    _reset_node(rig, node.node_id)
    assert _u(client, 0x2104) == 0
