"""The simulated node end to end: an in-process SimulatorHost and a canopen client on one virtual bus.

Every wait is on a frame (FrameLog.wait_for) or on a scheduler sentinel. Absence of a frame
is shown by ordering: the host handles frames one at a time, so once the answer to a later
request has arrived, an answer to an earlier one would already be in the log.
"""

from __future__ import annotations

import itertools
import json
import statistics
import struct

import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.quirk_effects import WritesPreopOnly
from encoder_conformance.profile.schema import DeviceProfile, resolve_node_id_expression
from encoder_conformance.sim.engine.faults import FaultSet
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.node import SimulatedNode
from tests import sim_rig
from tests.sim_rig import MINIMAL, WAIT_S, Rig

rig = sim_rig.rig  # the shared fixture

SAVE = b"save"
LOAD = b"load"


@pytest.fixture(scope="module")
def minimal_profile() -> DeviceProfile:
    return load_profile(MINIMAL).profile


@pytest.fixture(scope="module")
def wdga_profile() -> DeviceProfile:
    return load_profile("wachendorff-wdga-mt").profile




def upload_request(index: int, sub: int = 0) -> bytes:
    return struct.pack("<BHB4x", 0x40, index, sub)


def u32(client: canopen.RemoteNode, index: int, sub: int = 0) -> int:
    return int.from_bytes(client.sdo.upload(index, sub), "little")


def abort_code(client: canopen.RemoteNode, index: int, sub: int, data: bytes) -> int:
    with pytest.raises(SdoAbortedError) as info:
        client.sdo.download(index, sub, data)
    return int(info.value.code)


def booted(rig: Rig, profile: DeviceProfile, faults: tuple[str, ...] = ()) -> tuple[SimulatedNode, canopen.RemoteNode]:
    """A node of ``profile`` powered on and in pre-operational, its NVM in tmp_path/nvm.json."""
    return rig.boot(profile, faults=faults, nvm_name="nvm.json")


# -- boot-up and NMT --------------------------------------------------------------------------------


def test_bootup_on_power_on(rig, minimal_profile):
    """Power-on sends the boot-up frame 700h+node-id [1] 00 and enters pre-operational."""
    node = rig.add(minimal_profile)
    assert node.state is None
    boot = rig.power_on(node)
    assert boot is not None, "no boot-up after power-on"
    assert boot.dlc == 1
    assert node.state is NmtState.PRE_OPERATIONAL


def test_no_sdo_in_stopped(rig, minimal_profile):
    """Stopped: SDO requests are not answered; after enter-pre-operational they are again."""
    node, _ = booted(rig, minimal_profile)
    rig.nmt(0x02, node.node_id)  # stop
    silent_mark = rig.send(0x600 + node.node_id, upload_request(0x1000))
    rig.nmt(0x80, node.node_id)  # enter pre-operational
    answer = rig.raw_sdo(node.node_id, upload_request(0x1018, 1))
    assert answer is not None, "no SDO answer in pre-operational"
    answers = rig.log.since(silent_mark, lambda m: m.is_rx and m.arbitration_id == 0x580 + node.node_id)
    assert [bytes(m.data[1:4]) for m in answers] == [b"\x18\x10\x01"], "1000h was answered in stopped"


def test_nmt_start_and_stop_states(rig, minimal_profile):
    """NMT start -> operational, stop -> stopped, enter pre-op -> pre-operational; other node-ids ignored."""
    node, client = booted(rig, minimal_profile)
    rig.nmt(0x01, node.node_id + 1)  # another node
    rig.nmt(0x01, 0)  # broadcast start
    u32(client, 0x1000)  # any answer: the NMT frames before it have been handled
    assert node.state is NmtState.OPERATIONAL
    rig.nmt(0x02, node.node_id)
    rig.nmt(0x80, node.node_id)
    u32(client, 0x1000)
    assert node.state is NmtState.PRE_OPERATIONAL


def test_reset_communication_sends_bootup_and_reloads_1017(rig, minimal_profile):
    """Reset communication: boot-up again, 1017h back to its default, application values kept."""
    node, client = booted(rig, minimal_profile)
    client.sdo.download(0x1017, 0, struct.pack("<H", 200))
    client.sdo.download(0x6001, 0, struct.pack("<I", 2048))
    assert u32(client, 0x1017) == 200
    mark = rig.nmt(0x82, node.node_id)
    assert rig.wait_bootup(node.node_id, mark) is not None, "no boot-up after reset communication"
    assert u32(client, 0x1017) == 0
    assert u32(client, 0x6001) == 2048, "reset communication must not touch 6000h+"


def test_reset_node_reloads_application_values(rig, minimal_profile):
    """Reset node: boot-up and every unstored value back to its default."""
    node, client = booted(rig, minimal_profile)
    client.sdo.download(0x6001, 0, struct.pack("<I", 2048))
    mark = rig.nmt(0x81, node.node_id)
    assert rig.wait_bootup(node.node_id, mark) is not None
    assert u32(client, 0x6001) == 4096


def test_heartbeat_reports_the_state(rig, minimal_profile):
    """With 1017h set, heartbeats carry the NMT state (7Fh pre-operational, 05h operational)."""
    node, client = booted(rig, minimal_profile)
    hb = 0x700 + node.node_id
    mark = rig.log.mark()
    client.sdo.download(0x1017, 0, struct.pack("<H", 10))
    first = rig.log.wait_for(lambda m: m.is_rx and m.arbitration_id == hb, WAIT_S, mark)
    assert first is not None
    assert bytes(first.data) == b"\x7f"
    mark = rig.nmt(0x01, node.node_id)
    beat = rig.log.wait_for(lambda m: m.is_rx and m.arbitration_id == hb and m.data[0] == 0x05, WAIT_S, mark)
    assert beat is not None, "no operational heartbeat"


# -- store / restore ----------------------------------------------------------------------------------


def test_store_survives_power_cycle(rig, minimal_profile):
    """1010h sub 1 'save' writes the value to the NVM file; after a power cycle the value is back."""
    node, client = booted(rig, minimal_profile)
    client.sdo.download(0x6001, 0, struct.pack("<I", 2048))
    client.sdo.download(0x1010, 1, SAVE)
    stored = json.loads((rig.tmp_path / "nvm.json").read_text(encoding="utf-8"))["values"]
    assert stored["0x6001.0"] == 2048
    node.power_off()
    assert rig.power_on(node) is not None
    assert u32(client, 0x6001) == 2048


def test_unsaved_value_is_lost_at_power_cycle(rig, minimal_profile):
    """Without 'save', a power cycle brings the default back."""
    node, client = booted(rig, minimal_profile)
    client.sdo.download(0x6001, 0, struct.pack("<I", 2048))
    node.power_off()
    assert rig.power_on(node) is not None
    assert u32(client, 0x6001) == 4096


def test_restore_defaults_after_reset(rig, minimal_profile):
    """1011h sub 1 'load' keeps the current value until reset node; then the default is back."""
    node, client = booted(rig, minimal_profile)
    client.sdo.download(0x6001, 0, struct.pack("<I", 2048))
    client.sdo.download(0x1010, 1, SAVE)
    client.sdo.download(0x1011, 1, LOAD)
    assert u32(client, 0x6001) == 2048, "restore takes effect only at the next reset"
    mark = rig.nmt(0x81, node.node_id)
    assert rig.wait_bootup(node.node_id, mark) is not None
    assert u32(client, 0x6001) == 4096


@pytest.mark.parametrize(("index", "signature"), [(0x1010, b"savf"), (0x1011, b"save"), (0x1010, b"load")])
def test_wrong_signature_aborts_08000020(rig, minimal_profile, index, signature):
    """Store/restore with a wrong signature aborts 08000020h and changes nothing."""
    _, client = booted(rig, minimal_profile)
    assert abort_code(client, index, 1, signature) == 0x08000020
    assert not (rig.tmp_path / "nvm.json").exists()


# -- quirks ---------------------------------------------------------------------------------------------


def test_writes_preop_only_quirk(rig, wdga_profile):
    """WDGA: 2101h (node-id) is writable in pre-operational, refused in operational with the quirk's code."""
    params = wdga_profile.params_of(WritesPreopOnly)
    assert params is not None
    node, client = booted(rig, wdga_profile)
    client.sdo.download(0x2101, 0, bytes([node.node_id]))  # same value: allowed in pre-operational
    rig.nmt(0x01, node.node_id)
    u32(client, 0x1000)
    assert node.state is NmtState.OPERATIONAL
    assert abort_code(client, 0x2101, 0, bytes([node.node_id])) == params.abort_code


def test_node_id_object_quirk_takes_effect_at_reset(rig, wdga_profile):
    """WDGA: 2101h = 5 is saved at once and used after reset communication; $NODEID COB-IDs follow."""
    node, client = booted(rig, wdga_profile)
    client.sdo.download(0x2101, 0, b"\x05")
    assert u32(client, 0x2101) == 5, "the new node-id must not take effect before the reset"
    stored = json.loads((rig.tmp_path / "nvm.json").read_text(encoding="utf-8"))["values"]
    assert stored["0x2101.0"] == 5
    mark = rig.nmt(0x82, node.node_id)
    assert rig.wait_bootup(5, mark) is not None, "no boot-up on node-id 5"
    assert node.node_id == 5
    moved = rig.client(5)
    assert u32(moved, 0x1014) == 0x85
    assert u32(moved, 0x1800, 1) & 0x7FF == 0x185

def test_silent_until_bus_traffic(rig, wdga_profile):
    """WDGA twin: no boot-up after power-on until a frame is seen; then boot-up follows."""
    node = rig.add(wdga_profile)
    mark = rig.log.mark()
    node.power_on()
    delay_s = wdga_profile.simulator.bootup_delay_ms / 1000
    assert rig.scheduler_drained(10 * delay_s + 0.02)
    assert node.state is NmtState.INITIALISING
    assert rig.log.since(mark, lambda m: m.is_rx) == [], "the node sent something before any bus traffic"
    rig.send(0x80)  # a SYNC wakes it (bit rate detected)
    assert rig.wait_bootup(node.node_id, mark) is not None, "no boot-up after bus traffic"
    assert node.state is NmtState.PRE_OPERATIONAL


def test_minimal_profile_is_not_silent(rig, minimal_profile):
    """A profile without the quirk boots without any bus traffic (contrast to the WDGA twin)."""
    node = rig.add(minimal_profile)
    mark = rig.log.mark()
    node.power_on()
    assert rig.wait_bootup(node.node_id, mark) is not None


# -- faults ---------------------------------------------------------------------------------------------


def heartbeat_mean_ms(rig: Rig, node: SimulatedNode, client: canopen.RemoteNode, period_ms: int) -> float:
    hb = 0x700 + node.node_id
    mark = rig.log.mark()
    client.sdo.download(0x1017, 0, struct.pack("<H", period_ms))
    beats = rig.log.wait_count(lambda m: m.is_rx and m.arbitration_id == hb, 12, WAIT_S, mark)
    assert len(beats) == 12, f"only {len(beats)} heartbeats"
    stamps = [m.timestamp for m in beats[1:]]  # the first interval starts at the SDO write
    return statistics.fmean(b - a for a, b in itertools.pairwise(stamps)) * 1000


@pytest.mark.parametrize(("faults", "factor"), [((), 1.0), (("heartbeat_slow_20pct",), 1.2)], ids=["none", "slow"])
def test_heartbeat_period_and_slow_fault(rig, minimal_profile, faults, factor):
    """Heartbeat mean period equals 1017h (20 ms); heartbeat_slow_20pct makes it 24 ms."""
    node, client = booted(rig, minimal_profile, faults)
    mean = heartbeat_mean_ms(rig, node, client, 20)
    assert abs(mean - 20 * factor) < 1.5, f"mean heartbeat period {mean:.2f} ms"


@pytest.mark.parametrize(("faults", "delta"), [((), 0), (("wrong_vendor_id",), 1)], ids=["none", "wrong_vendor_id"])
def test_wrong_vendor_id_fault(rig, minimal_profile, faults, delta):
    """1018h sub 1 reads the profile's vendor-id, or one more with wrong_vendor_id."""
    _, client = booted(rig, minimal_profile, faults)
    assert u32(client, 0x1018, 1) == minimal_profile.identity.vendor_id + delta


def test_no_sdo_response_fault(rig, minimal_profile):
    """no_sdo_response: SDO requests go unanswered while NMT and heartbeat still work."""
    node, _ = booted(rig, minimal_profile, ("no_sdo_response",))
    mark = rig.send(0x600 + node.node_id, upload_request(0x1000))
    rig.nmt(0x81, node.node_id)  # the boot-up after this proves the request was handled first
    assert rig.wait_bootup(node.node_id, mark) is not None
    assert rig.log.since(mark, lambda m: m.is_rx and m.arbitration_id == 0x580 + node.node_id) == []


def test_unknown_fault_is_refused():
    """FaultSet refuses names it does not know, listing the known ones."""
    with pytest.raises(ValueError, match=r"known faults: .*wrong_vendor_id"):
        FaultSet(["nonsense"])


# -- PDO and position -------------------------------------------------------------------------------------


def test_sync_tpdo_sent_on_sync_in_operational(rig, wdga_profile):
    """WDGA TPDO2 (type 1, 6004h mapped) is sent on every SYNC in operational, not in pre-operational."""
    node, client = booted(rig, wdga_profile)
    cob = resolve_node_id_expression(wdga_profile.entry(0x1801, 1).default, node.node_id) & 0x7FF
    assert cob == 0x280 + node.node_id
    assert wdga_profile.entry(0x1801, 2).default == 1
    # pre-operational: a SYNC sends no TPDO (the SDO answer after it shows the SYNC was handled)
    mark = rig.send(0x80)
    u32(client, 0x1000)
    assert rig.log.since(mark, lambda m: m.is_rx and m.arbitration_id == cob) == []
    rig.nmt(0x01, node.node_id)
    node.shaft.turn_by(0.25)
    expected = u32(client, 0x6004)
    mark = rig.send(0x80)
    pdo = rig.log.wait_for(lambda m: m.is_rx and m.arbitration_id == cob, WAIT_S, mark)
    assert pdo is not None, "no TPDO2 after SYNC in operational"
    assert int.from_bytes(pdo.data[:4], "little") == expected


def test_preset_sets_the_position(rig, minimal_profile):
    """Writing 6003h (preset) makes 6004h read the preset value at the current shaft angle."""
    node, client = booted(rig, minimal_profile)
    node.shaft.turn_by(0.3)
    assert u32(client, 0x6004) == int(0.3 * 4096)
    client.sdo.download(0x6003, 0, struct.pack("<I", 1000))
    assert u32(client, 0x6004) == 1000
    node.shaft.turn_by(0.25)
    assert u32(client, 0x6004) == 1000 + 1024


def test_segmented_read_of_device_name(rig, wdga_profile):
    """1008h (10 characters) is read through a segmented upload."""
    _, client = booted(rig, wdga_profile)
    assert client.sdo.upload(0x1008, 0) == b"WDGA-MT-CO"


def test_sdo_abort_codes_of_the_twin(rig, minimal_profile):
    """Missing object 06020000h, missing sub 06090011h, write ro 06010002h, read wo 06010001h, too high 06090031h."""
    _, client = booted(rig, minimal_profile)
    assert abort_code(client, 0x1234, 0, b"\x00") == 0x06020000
    assert abort_code(client, 0x1018, 9, b"\x00\x00\x00\x00") == 0x06090011
    assert abort_code(client, 0x1000, 0, b"\x00\x00\x00\x00") == 0x06010002
    assert abort_code(client, 0x6001, 0, struct.pack("<I", 5000)) == 0x06090031
    with pytest.raises(SdoAbortedError) as info:
        client.sdo.upload(0x2000, 0)
    assert int(info.value.code) == 0x06010001



@pytest.fixture
def inhibit_profile(tmp_path) -> DeviceProfile:
    """The minimal encoder with an inhibit time (1800h sub 3) and a second, SYNC-driven TPDO."""
    text = MINIMAL.read_text(encoding="utf-8")
    text = text.replace(
        "      5: {name: Event timer, type: U16, access: rw, default: 0, persisted_by: store_comm}",
        "      3: {name: Inhibit time, type: U16, access: rw, default: 0, persisted_by: store_comm}\n"
        "      5: {name: Event timer, type: U16, access: rw, default: 0, persisted_by: store_comm}", 1)
    assert "Inhibit time" in text
    path = tmp_path / "inhibit" / MINIMAL.name  # a profile's file name is its id
    path.parent.mkdir()
    path.write_text(text, encoding="utf-8")
    return load_profile(str(path)).profile


def _configure_tpdo1(client: canopen.RemoteNode, kind: int, inhibit_100us: int, timer_ms: int) -> None:
    client.sdo.download(0x1800, 2, bytes([kind]))
    client.sdo.download(0x1800, 3, struct.pack("<H", inhibit_100us))
    client.sdo.download(0x1800, 5, struct.pack("<H", timer_ms))


def test_inhibit_time_delays_event_timer_tpdo_not_drops_it(rig, inhibit_profile):
    """CiA 301: an event inside the inhibit time is sent when it ends. Timer 40 ms, inhibit 50 ms: frames
    50 ms apart (dropping the early events would space them 80 ms apart)."""
    node, client = booted(rig, inhibit_profile)
    _configure_tpdo1(client, 255, 500, 40)
    cob = 0x180 + node.node_id
    mark = rig.nmt(0x01, node.node_id)
    frames = rig.log.wait_count(lambda m: m.is_rx and m.arbitration_id == cob, 7, 2.0, mark)
    gaps = [(b.timestamp - a.timestamp) * 1000 for a, b in itertools.pairwise(frames[1:])]
    assert len(frames) == 7
    assert min(gaps) >= 48, gaps  # never closer than the inhibit time
    assert statistics.median(gaps) < 65, gaps  # delayed to the inhibit time's end, not dropped


def test_inhibit_time_does_not_apply_to_sync_tpdos(rig, inhibit_profile):
    """CiA 301 limits the inhibit time to types 254/255: a type-1 TPDO answers every SYNC."""
    node, client = booted(rig, inhibit_profile)
    _configure_tpdo1(client, 1, 10000, 0)  # 1 s inhibit, ignored for a SYNC-driven TPDO
    cob = 0x180 + node.node_id
    rig.nmt(0x01, node.node_id)
    u32(client, 0x1000)  # the start was handled
    mark = rig.log.mark()
    for _ in range(3):
        sync = rig.send(0x80)
        assert rig.frame(cob, sync) is not None, "a SYNC inside the inhibit time got no TPDO"
    assert len(rig.frames(cob, mark)) == 3


def test_non_encoder_profile_keeps_its_6004h(rig, tmp_path):
    """A profile that is not an encoder (capabilities.encoder: false) gets no computed position: its 6004h
    holds what was written, whatever the shaft does (issue 9: the twin wrote encoder values into any 6004h)."""
    text = MINIMAL.read_text(encoding="utf-8")
    text = text.replace("capabilities: {cia406: true,", "capabilities: {encoder: false, cia406: false,", 1)
    text = text.replace("encoder_class: C2, ", "", 1).replace("scaling: true, preset: true", "scaling: false", 1)
    path = tmp_path / "not-an-encoder" / MINIMAL.name
    path.parent.mkdir()
    path.write_text(text, encoding="utf-8")
    profile = load_profile(str(path)).profile
    node, client = booted(rig, profile)
    before = u32(client, 0x6004)
    node.shaft.turn_by(0.3)
    assert u32(client, 0x6004) == before
