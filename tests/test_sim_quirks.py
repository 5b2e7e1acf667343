"""Documented quirks played by the simulated twins (in-process SimulatorHost + canopen client).

Every wait is on a frame (FrameLog.wait_for) or on a scheduler sentinel, never a fixed sleep.
Absence of a frame is shown by ordering: the host handles frames one at a time, so once the
answer to a later request has arrived, an answer to an earlier one would already be in the log.
Profiles with multi-second boot times are copied with short delays (``fast``).
"""

from __future__ import annotations

import itertools
import statistics
import struct
import time
from typing import Any

import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.quirks import QuirkBase, parse_quirk
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.control_server import LocalControl
from encoder_conformance.sim.engine.faults import FaultSet
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import NonVolatileMemory
from tests import sim_rig
from tests.sim_rig import MINIMAL, WAIT_S

rig = sim_rig.rig  # the shared fixture

STORE_2300 = bytes.fromhex("22 00 23 00 55 AA AA 55")
REBOOT_MS = 150



def fast(profile: DeviceProfile, quirk_params: dict[str, dict[str, Any]] | None = None,
         extra: dict[str, QuirkBase] | None = None) -> DeviceProfile:
    """The profile with a 5 ms boot-up delay, some quirk params replaced and ``extra`` quirks added."""
    quirks = dict(profile.quirks)
    for quirk_id, params in (quirk_params or {}).items():
        old = quirks[quirk_id].params
        new = type(old).model_validate({**old.model_dump(exclude_unset=True), **params})
        quirks[quirk_id] = quirks[quirk_id].model_copy(update={"params": new})
    quirks.update(extra or {})
    simulator = profile.simulator.model_copy(update={"bootup_delay_ms": 5})
    return profile.model_copy(update={"simulator": simulator, "quirks": quirks})


def quirk(effect: str, **params: Any) -> QuirkBase:
    return parse_quirk({"title": f"test {effect}", "manual": "self-test", "description": "self-test", "effect": effect,
                        "params": params})




def read_u(client: canopen.RemoteNode, index: int, sub: int = 0) -> int:
    return int.from_bytes(client.sdo.upload(index, sub), "little")


def read_i(client: canopen.RemoteNode, index: int, sub: int = 0) -> int:
    return int.from_bytes(client.sdo.upload(index, sub), "little", signed=True)


def write(client: canopen.RemoteNode, index: int, sub: int, value: int, size: int) -> None:
    client.sdo.download(index, sub, value.to_bytes(size, "little", signed=value < 0))


def abort_code(client: canopen.RemoteNode, index: int, sub: int, data: bytes) -> int:
    with pytest.raises(SdoAbortedError) as info:
        client.sdo.download(index, sub, data)
    return int(info.value.code)


# -- FRABA POSITAL: store through 2300h, manufacturer encoder objects, fixed PDO layout -------------


@pytest.fixture(scope="module")
def posital() -> DeviceProfile:
    profile = load_profile("fraba-posital-awc58-c2-mt").profile
    return fast(profile, {"store-via-2300h-reboots": {"reboot_ms": REBOOT_MS}})


def test_posital_store_2300h_no_reply_reboot_bootup(rig, posital):
    """2300h = 55 AA AA 55: no SDO reply, silent while rebooting, boot-up after reboot_ms, value stored."""
    node, client = rig.boot(posital)
    write(client, 0x2200, 0, 200, 2)
    mark = rig.send(0x601, STORE_2300)
    rig.send(0x601, bytes.fromhex("40 00 22 00 00 00 00 00"))  # ignored while rebooting
    boot = rig.wait_bootup(1, mark)
    assert boot is not None, "no boot-up after the store"
    sent = next(m for m in rig.log.since(mark) if not m.is_rx)
    assert boot.timestamp - sent.timestamp >= REBOOT_MS / 1000 * 0.9
    assert [m for m in rig.log.since(mark, lambda m: m.is_rx) if m.timestamp < boot.timestamp] == []
    assert node.state is NmtState.PRE_OPERATIONAL
    assert read_u(client, 0x2200) == 200
    assert rig.frames(0x581, mark)[0].data[0] == 0x4B, "only the read after the boot-up was answered"
    node.power_cycle()
    assert rig.wait_bootup(1, rig.log.mark(), timeout=WAIT_S) is not None
    assert read_u(client, 0x2200) == 200, "the stored value must survive a power cycle"


def test_posital_wrong_store_signature_refused_without_reboot(rig, posital):
    """Another value than 55 AA AA 55: the twin's chosen answer, abort 08000020h, nothing stored, no reboot."""
    node, client = rig.boot(posital)
    write(client, 0x2200, 0, 300, 2)
    reply = rig.raw_sdo(1, bytes.fromhex("22 00 23 00 73 61 76 65"))
    assert reply is not None
    assert reply.data[0] == 0x80
    assert struct.unpack_from("<I", reply.data, 4)[0] == 0x08000020
    assert node.state is NmtState.PRE_OPERATIONAL
    assert read_u(client, 0x2200) == 300
    mark = rig.nmt(0x81, 1)
    assert rig.wait_bootup(1, mark) is not None
    assert read_u(client, 0x2200) == 100, "nothing was stored"


def test_posital_process_value_scaling_direction_and_preset(rig, posital):
    """2000h follows the shaft through 2100h bit 0, 2101h/2102h scaling and the 2103h preset (stored)."""
    node, client = rig.boot(posital)
    node.shaft.set_turns(0.5)
    assert read_u(client, 0x2000) == 2048
    write(client, 0x2101, 0, 2048, 2)  # the manual's example: AU 2048, GA = 2^24 * 2048 / 4096
    write(client, 0x2102, 0, 0x800000, 4)
    assert read_u(client, 0x2000) == 1024
    write(client, 0x2100, 0, 1, 2)  # counting direction CCW
    assert read_u(client, 0x2000) == 0x800000 - 1024
    write(client, 0x2100, 0, 0, 2)
    write(client, 0x2103, 0, 5000, 4)
    assert read_u(client, 0x2000) == 5000
    node.shaft.turn_by(0.25)
    assert read_u(client, 0x2000) == 5000 + 512
    mark = rig.send(0x601, STORE_2300)
    assert rig.wait_bootup(1, mark) is not None
    assert read_u(client, 0x2000) == 5000 + 512, "preset, scaling and offset survive the store reboot"


def test_posital_limit_switch_flags_in_tpdo_only(rig, posital):
    """2100h bits 1/2 enable bit 30 (below 2104h) and bit 31 (above 2105h) in the TPDO; SDO shows the position."""
    node, client = rig.boot(posital)
    write(client, 0x2104, 0, 1000, 4)
    write(client, 0x2105, 0, 3000, 4)
    write(client, 0x2100, 0, 0x6, 2)
    rig.nmt(0x01, 1)
    for turns, flags in ((500 / 4096, 1 << 30), (2000 / 4096, 0), (1000 / 4096, 0), (3500 / 4096, 1 << 31)):
        node.shaft.set_turns(turns)
        position = round(turns * 4096)
        pdo = rig.frame(0x281, rig.send(0x80))
        assert pdo is not None, "no PDO 2 after SYNC"
        assert pdo.dlc == 4
        assert int.from_bytes(pdo.data, "little") == position | flags, f"position {position}"
        assert read_u(client, 0x2000) == position, "SDO reads of 2000h carry no flags (applies_to: tpdo)"


def test_posital_cyclic_pdo_period_from_2200h(rig, posital):
    """PDO 1 (181h) is sent every 2200h ms in operational, 4 bytes, not on SYNC; bit 31 of 1800h.1 stops it."""
    _, client = rig.boot(posital)
    write(client, 0x1802, 1, 0x80000281, 4)  # sync PDO off: only PDO 1 remains
    write(client, 0x2200, 0, 20, 2)
    mark = rig.nmt(0x01, 1)
    frames = rig.log.wait_count(lambda m: m.is_rx and m.arbitration_id == 0x181, 11, WAIT_S, mark)
    assert len(frames) == 11
    mean_ms = statistics.fmean(b.timestamp - a.timestamp for a, b in itertools.pairwise(frames)) * 1000
    assert abs(mean_ms - 20) < 3, f"mean period {mean_ms:.1f} ms"
    assert all(m.dlc == 4 for m in frames)
    write(client, 0x1800, 1, 0x80000181, 4)
    stopped = rig.log.mark()
    assert rig.scheduler_drained(0.06)
    assert rig.frames(0x181, stopped) == [], "PDO 1 still sent with COB-ID bit 31 set"
    assert rig.frames(0x281, mark) == []


def test_posital_sync_counter_every_nth_sync(rig, posital):
    """1802h sub 2 = 3: PDO 2 (281h) answers every 3rd SYNC (9 SYNCs -> 3 PDOs); nothing in pre-operational."""
    _, client = rig.boot(posital)
    write(client, 0x1800, 1, 0x80000181, 4)  # cyclic PDO off
    write(client, 0x1802, 2, 3, 1)
    mark = rig.send(0x80)
    read_u(client, 0x2000)  # the SYNC before this read was handled
    assert rig.frames(0x281, mark) == [], "PDO 2 in pre-operational"
    rig.nmt(0x01, 1)
    mark = rig.log.mark()
    counts = []
    for _ in range(9):
        rig.send(0x80)
        read_u(client, 0x2000)  # the SYNC before this read was handled
        counts.append(len(rig.frames(0x281, mark)))
    assert counts == [0, 0, 1, 1, 1, 2, 2, 2, 3]


def test_posital_rtr_polled_mode_in_operational_only(rig, posital):
    """An RTR on 181h is answered with the 4-byte process value in operational, ignored in pre-operational."""
    node, client = rig.boot(posital)
    write(client, 0x2200, 0, 0xFFFF, 2)  # no cyclic frame during the test
    node.shaft.set_turns(0.25)
    mark = rig.send(0x181, remote=True)
    read_u(client, 0x2000)
    assert rig.frames(0x181, mark) == [], "RTR answered in pre-operational"
    rig.nmt(0x01, 1)
    read_u(client, 0x2000)
    answer = rig.log.wait_for(lambda m: m.is_rx and m.arbitration_id == 0x181 and not m.is_remote_frame,
                              WAIT_S, rig.send(0x181, remote=True))
    assert answer is not None
    assert answer.dlc == 4
    assert int.from_bytes(answer.data, "little") == 1024


# -- SIKO: scaling-bit gate, position frozen while writes execute, signed position ------------------


@pytest.fixture(scope="module")
def siko_mt() -> DeviceProfile:
    return fast(load_profile("siko-wx58m-1012-mt").profile)


def test_siko_writes_need_scaling_bit(rig, siko_mt):
    """6001h-6003h and 2001h are refused with 08000022h while 6000h bit 2 is clear, accepted when it is set."""
    _, client = rig.boot(siko_mt)
    for index, value in ((0x6001, 512), (0x6002, 1 << 20), (0x6003, 100), (0x2001, 100)):
        assert abort_code(client, index, 0, struct.pack("<I", value)) == 0x08000022, f"{index:04X}h"
    write(client, 0x6000, 0, 0x04, 2)
    write(client, 0x6001, 0, 512, 4)
    assert read_u(client, 0x6001) == 512


def test_siko_position_frozen_while_write_executes(rig, siko_mt):
    """After a 6003h write the position keeps its old value for 160 ms (durations_ms), then shows the preset."""
    node, client = rig.boot(siko_mt)
    write(client, 0x6000, 0, 0x04, 2)
    assert rig.scheduler_drained(0.077)  # 6000h with the scaling bit set: 77 ms
    node.shaft.set_turns(0.5)
    before = read_i(client, 0x6004)
    assert before == 512
    start = time.monotonic()
    write(client, 0x6003, 0, 1000, 4)
    node.shaft.turn_by(0.25)
    assert read_i(client, 0x6004) == before, "position updated during the processing time"
    assert rig.scheduler_drained(0.160)
    assert time.monotonic() - start >= 0.160
    assert read_i(client, 0x6004) == 1000 + 256


def test_siko_signed_position_and_preset(rig, siko_mt):
    """Multiturn 6004h is SIGNED32 over -TMR/2 .. TMR/2 - 1: negative angles, negative preset, TPDO bytes."""
    node, client = rig.boot(siko_mt)
    node.shaft.set_turns(-0.25)
    assert read_i(client, 0x6004) == -256
    assert client.sdo.upload(0x6004, 0) == (-256).to_bytes(4, "little", signed=True)
    node.shaft.set_turns(2048)  # half the 4096 revolutions: the top of the positive half
    assert read_i(client, 0x6004) == -2097152
    node.shaft.set_turns(2048 - 1 / 1024)
    assert read_i(client, 0x6004) == 2097151
    write(client, 0x6000, 0, 0x04, 2)
    write(client, 0x6003, 0, -1000, 4)
    assert rig.scheduler_drained(0.160)
    assert read_i(client, 0x6004) == -1000
    node.shaft.turn_by(-0.5)
    assert read_i(client, 0x6004) == -1512
    assert abort_code(client, 0x6003, 0, struct.pack("<i", -2097153)) == 0x06090030  # below min, SIKO's code


def test_siko_singleturn_position_stays_unsigned(rig):
    """Singleturn SIKO: no negative half, 0 .. 1023 for 10 bit."""
    node, client = rig.boot(fast(load_profile("siko-wx58m-10st").profile))
    node.shaft.set_turns(-0.25)
    assert read_i(client, 0x6004) == 768


def test_siko_abort_code_quirks(rig, siko_mt):
    """abort_code quirks: too high / too low 06090030h, too short 06070010h (SIKO's abort list)."""
    _, client = rig.boot(siko_mt)
    assert abort_code(client, 0x2800, 0, b"\x65") == 0x06090030  # 101 > 100
    write(client, 0x6000, 0, 0x04, 2)
    assert abort_code(client, 0x6001, 0, struct.pack("<I", 0)) == 0x06090030  # below min 1
    assert abort_code(client, 0x6001, 0, b"\x01") == 0x06070010


# -- SIKO: send-repeat counters 2800h/2801h, PDO2 disabled at every init -----------------------------


def _pdo1(m) -> bool:
    return m.is_rx and m.arbitration_id == 0x181


def test_siko_pdo1_timer_only_without_send_repeat_counter(rig, siko_mt):
    """2800h = 0: PDO1 (type FEh) follows only its event timer; timer 0 sends nothing, not even on a change."""
    node, client = rig.boot(siko_mt)
    mark = rig.nmt(0x01, 1)
    node.shaft.turn_by(0.25)
    assert rig.scheduler_drained(0.03)  # several change polls
    assert rig.frames(0x181, mark) == [], "PDO1 sent on a change with 2800h = 0"
    rig.nmt(0x80, 1)
    write(client, 0x1800, 5, 10, 2)
    mark = rig.nmt(0x01, 1)
    assert len(rig.log.wait_count(_pdo1, 5, WAIT_S, mark)) == 5, "PDO1 not sent cyclically by the event timer"


@pytest.mark.parametrize("faults", [(), ("send_repeat_counter_ignored",)], ids=["twin", "fault"])
def test_siko_pdo1_sent_n_times_per_change(rig, siko_mt, faults):
    """2800h = 3, timer 0: each change gives PDO1 three times, one per change poll; none while still."""
    expected = 1 if faults else 3
    node, client = rig.boot(siko_mt, faults=faults)
    write(client, 0x2800, 0, 3, 1)
    mark = rig.nmt(0x01, 1)
    assert rig.scheduler_drained(0.03)
    assert rig.frames(0x181, mark) == [], "PDO1 without a change"
    for turn in (1, 2):
        mark = rig.log.mark()
        node.shaft.turn_by(0.25)
        frames = rig.log.wait_count(_pdo1, expected, WAIT_S, mark)
        assert rig.scheduler_drained(0.03)
        assert len(rig.frames(0x181, mark)) == expected, f"change {turn}"
        assert {bytes(m.data) for m in frames} == {struct.pack("<i", read_i(client, 0x6004))}


def test_siko_pdo1_timer_wins_over_send_repeat_counter(rig, siko_mt):
    """2800h = 3 with timer 20 ms: PDO1 stays timer-driven (the change trigger needs timer 0)."""
    node, client = rig.boot(siko_mt)
    write(client, 0x2800, 0, 3, 1)
    write(client, 0x1800, 5, 20, 2)
    mark = rig.nmt(0x01, 1)
    first = rig.log.wait_for(_pdo1, WAIT_S, mark)
    assert first is not None
    node.shaft.turn_by(0.25)
    frames = rig.log.wait_count(_pdo1, 4, WAIT_S, mark)
    gaps = [b.timestamp - a.timestamp for a, b in itertools.pairwise(frames)]
    assert min(gaps) > 0.010, f"PDO1 sent between timer periods: {gaps}"


@pytest.mark.parametrize("faults", [(), ("send_repeat_counter_ignored",)], ids=["twin", "fault"])
def test_siko_pdo2_limited_by_2801h(rig, siko_mt, faults):
    """1801h sub 2 = 3, 2801h = 4: PDO2 after SYNC 3, 6, 9, 12 and no more; a change restarts the count."""
    node, client = rig.boot(siko_mt, faults=faults)
    write(client, 0x1801, 1, 0x281, 4)
    write(client, 0x1801, 2, 3, 1)
    write(client, 0x2801, 0, 4, 1)
    rig.nmt(0x01, 1)
    for turn in (0, 0.25):
        node.shaft.turn_by(turn)
        mark = rig.log.mark()
        counts = []
        for _ in range(18):
            rig.send(0x80)
            read_u(client, 0x1000)  # the SYNC before this read was handled
            counts.append(len(rig.frames(0x281, mark)))
        if faults:
            assert counts[-1] == 6, "the fault sends on every 3rd SYNC without limit"
        else:
            assert counts == [0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4, 4, 4, 4, 4], f"turned by {turn}"


@pytest.mark.parametrize("faults", [(), ("forced_bits_not_applied",)], ids=["twin", "fault"])
def test_siko_pdo2_disabled_again_at_every_init(rig, siko_mt, faults):
    """1801h sub 1 bit 31 is set again at power-on, 81h and 82h; the stored value stays 281h."""
    node, client = rig.boot(siko_mt, faults=faults)
    expected = 0x281 if faults else 0x80000281
    for init in (0x81, 0x82, "power"):
        write(client, 0x1801, 1, 0x281, 4)
        assert read_u(client, 0x1801, 1) == 0x281
        if init == "power":
            mark = rig.log.mark()
            node.power_cycle()
            assert rig.wait_bootup(1, mark) is not None
        else:
            assert rig.wait_bootup(1, rig.nmt(init, 1)) is not None
        assert read_u(client, 0x1801, 1) == expected, f"after {init}"
        assert node.nvm.get((0x1801, 1)) == 0x281, "the stored value itself is kept"


# -- WayCon MH: the redundant interface's second node -------------------------------------------------


def test_waycon_mh_second_node_on_the_bus(rig):
    """waycon-mh: node 7 and its sibling 8 boot; broadcast NMT reaches both, addressed NMT only one."""
    profile = fast(load_profile("waycon-mh").profile)
    node = rig.host.add_node(profile, None, rig.tmp_path / "nvm.json", FaultSet(), power_on=False)
    [sibling] = rig.host.add_siblings(power_on=False)
    assert (sibling.node_id, sibling.profile.id) == (8, "waycon-mh-node2")
    assert rig.host.node() is node
    mark = rig.log.mark()
    LocalControl(rig.host).power_on()  # one power supply for both nodes
    assert rig.wait_bootup(7, mark) is not None
    assert rig.wait_bootup(8, mark) is not None
    one, two = rig.client(7), rig.client(8)
    assert (read_u(one, 0x2101), read_u(two, 0x2101)) == (7, 8)
    rig.nmt(0x01, 0)
    read_u(one, 0x1000), read_u(two, 0x1000)
    assert (node.state, sibling.state) == (NmtState.OPERATIONAL, NmtState.OPERATIONAL)
    rig.nmt(0x02, 8)
    rig.nmt(0x80, 8)
    read_u(two, 0x1000)
    assert (node.state, sibling.state) == (NmtState.OPERATIONAL, NmtState.PRE_OPERATIONAL)
    mark = rig.log.mark()
    LocalControl(rig.host).power_cycle()
    assert rig.wait_bootup(7, mark) is not None
    assert rig.wait_bootup(8, mark) is not None


def test_waycon_mh_node2_sibling_is_node_1(rig):
    """waycon-mh-node2 (node 8): the sibling is node 7 playing waycon-mh; a taken node-id adds no sibling."""
    profile = fast(load_profile("waycon-mh-node2").profile)
    rig.host.add_node(profile, None, None, FaultSet(), power_on=False)
    [sibling] = rig.host.add_siblings(power_on=False)
    assert (sibling.configured_node_id, sibling.profile.id) == (7, "waycon-mh")
    assert rig.host.add_siblings() == []


# -- effects no shipped profile uses yet (minimal encoder with the quirk added) ---------------------


def test_store_object_reads_back_quirk(rig):
    """store_object_reads_back: 1010h/1011h subs read the quirk's value instead of the capability word."""
    profile = fast(load_profile(MINIMAL).profile, extra={"reads-back": quirk("store_object_reads_back", value=0)})
    _, client = rig.boot(profile)
    assert (read_u(client, 0x1010, 1), read_u(client, 0x1011, 1)) == (0, 0)
    assert read_u(client, 0x1010, 0) == 1


def test_store_automatic_quirk(rig):
    """store_automatic: a written value is in NVM at once and survives a power cycle without 'save'."""
    profile = fast(load_profile(MINIMAL).profile, extra={"auto": quirk("store_automatic")})
    node, client = rig.boot(profile)
    write(client, 0x6001, 0, 2048, 4)
    assert NonVolatileMemory(rig.tmp_path / "nvm-minimal-encoder.json").get((0x6001, 0)) == 2048
    node.power_cycle()
    assert rig.wait_bootup(5, rig.log.mark()) is not None
    assert read_u(client, 0x6001) == 2048


def test_wdga_cob_ids_follow_node_id_until_store(rig):
    """WDGA: 1800h.1 follows a 2101h node-id change until 1010h sub 2 'save'; 1011h sub 2 'load' re-enables it."""
    node, client = rig.boot(load_profile("wachendorff-wdga-mt").profile)

    def move_to(node_id: int) -> canopen.RemoteNode:
        current = rig.client(node.node_id)
        current.sdo.download(0x2101, 0, bytes([node_id]))
        mark = rig.nmt(0x82, node.node_id)
        assert rig.wait_bootup(node_id, mark) is not None
        return rig.client(node_id)

    client = move_to(5)
    assert read_u(client, 0x1800, 1) & 0x7FF == 0x185
    client.sdo.download(0x1010, 2, b"save")
    client = move_to(6)
    assert read_u(client, 0x1800, 1) & 0x7FF == 0x185, "stored COB-ID must stay"
    client.sdo.download(0x1011, 2, b"load")
    client = move_to(9)
    assert read_u(client, 0x1800, 1) & 0x7FF == 0x189, "after restore the COB-ID follows again"


def test_waycon_node_id_takes_effect_only_after_2105h_save(rig):
    """node_id_object with a store object (WayCon 2101h + 2105h 'save'): unsaved, reset keeps node 7."""
    _, client = rig.boot(fast(load_profile("waycon-sx").profile))
    write(client, 0x2101, 0, 20, 1)
    assert rig.wait_bootup(7, rig.nmt(0x81, 7)) is not None, "unsaved node-id must not take effect"
    write(client, 0x2101, 0, 20, 1)
    client.sdo.download(0x2105, 0, b"save")
    assert rig.wait_bootup(20, rig.nmt(0x81, 7)) is not None, "no boot-up on the saved node-id 20"


def test_faulhaber_store_app_subindex_follows_the_profile_labels(rig):
    """FAULHABER 1010h sub 3 stores what the profile labels store_app, 2400h.03 (node-id) included."""
    node, client = rig.boot(fast(load_profile("faulhaber-mc5005").profile))
    old = node.node_id
    client.sdo.download(0x2400, 3, bytes([20]))
    client.sdo.download(0x1010, 3, b"save")
    assert rig.wait_bootup(20, rig.nmt(0x81, old)) is not None, "no boot-up on the stored node-id 20"
