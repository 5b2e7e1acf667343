"""The LSS master (dut/lss/lss_master.py) against the twin's LSS slaves (sim/engine/lss_slave.py) on a private virtual
bus.

Issue 10: fastscan finds one unconfigured device in < 1 s and eight on one bus in < 5 s (canopen's LssMaster
took 16.9 s for one); every service answers as CiA 305 says. A request keeps one frame time after an answer, as a
wire would (CANopenNode drops a request that comes while it is still finishing its answer).
"""

from __future__ import annotations

import itertools
import threading
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass

import can
import pytest

from encoder_conformance.cia.cia305 import MASTER_COB_ID, SLAVE_COB_ID, UNCONFIGURED_NODE_ID, LssState
from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.lss import lss_find, lss_master
from encoder_conformance.dut.lss.lss_find import WIDEST_WINDOW, scan_unconfigured
from encoder_conformance.dut.lss.lss_master import FRAME_BITS, FRAME_S, LssAddress, LssMaster
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.sim.engine.lss_slave import LssSlave
from tests import sim_rig

rig = sim_rig.rig  # the shared simulator fixture

ALL_SERVICES = frozenset({"switch_global", "switch_selective", "configure_node_id", "configure_bit_timing",
                          "activate_bit_timing", "store_configuration", "inquire_identity", "inquire_node_id",
                          "identify_remote_slave", "identify_non_configured", "fastscan"})
VENDOR, PRODUCT, REVISION = 0x00000147, 0x00000030, 0x00010000
RESPONSE_S = 0.01  # the twins answer within a millisecond; a missing answer costs this
SPOILED_SCANS = 3  # scans in a row a loaded host may spoil before the test gives up


@dataclass
class LssBus:
    master: LssMaster
    slaves: list[LssSlave]
    node_ids: list[int]


@pytest.fixture
def lss_bus(request) -> Iterator[LssBus]:
    """``request.param`` (default 1) unconfigured slaves with serials 1000, 1001, ... and a master; a tuple (count,
    seconds): slaves whose every answer comes that much later (a loaded bench PC or a slow link)."""
    count, delay_s = (param, 0.0) if isinstance(param := getattr(request, "param", 1), int) else param
    channel = f"lss-{uuid.uuid4().hex[:8]}"
    slave_side = can.Bus(interface="virtual", channel=channel)
    master_side = can.Bus(interface="virtual", channel=channel)
    node_ids = [UNCONFIGURED_NODE_ID] * count

    def send_answer(data: bytes) -> None:
        slave_side.send(can.Message(arbitration_id=SLAVE_COB_ID, data=data, is_extended_id=False))

    def answer(data: bytes) -> None:
        if delay_s:
            threading.Timer(delay_s, send_answer, (data,)).start()
        else:
            send_answer(data)

    slaves = [LssSlave(ALL_SERVICES, lambda n=n: (VENDOR, PRODUCT, REVISION, 1000 + n),
                       lambda n=n: node_ids[n], answer) for n in range(count)]

    def dispatch(msg: can.Message) -> None:
        if msg.arbitration_id == MASTER_COB_ID:
            for slave in slaves:
                slave.on_frame(bytes(msg.data))

    log = FrameLog()

    def send(cob_id: int, data: bytes) -> None:
        msg = can.Message(arbitration_id=cob_id, data=data, is_extended_id=False)
        log.record_sent(msg)
        master_side.send(msg)

    notifiers = [can.Notifier(slave_side, [dispatch], timeout=0.02), can.Notifier(master_side, [log], timeout=0.02)]
    yield LssBus(LssMaster(send, log, RESPONSE_S), slaves, node_ids)
    for notifier in notifiers:
        notifier.stop()
    slave_side.shutdown()
    master_side.shutdown()


def test_fastscan_finds_one_unconfigured_slave_in_under_a_second(lss_bus):
    start = time.perf_counter()
    found = lss_bus.master.fastscan()
    elapsed = time.perf_counter() - start
    assert found == LssAddress(VENDOR, PRODUCT, REVISION, 1000)
    assert lss_bus.slaves[0].state is LssState.CONFIGURATION
    print(f"\nfastscan, one slave, no part known: {elapsed:.2f} s, {lss_bus.master.steps} frames")
    assert elapsed < 1.0, f"fastscan of one slave took {elapsed:.2f} s ({lss_bus.master.steps} frames)"


@pytest.mark.parametrize("lss_bus", [8], indirect=True)
def test_fastscan_finds_eight_slaves_in_under_five_seconds(lss_bus):
    """Each found slave gets a node-ID and leaves the scan; vendor and product come from the profile."""
    master, found, spoiled = lss_bus.master, [], 0
    start = time.perf_counter()
    for node_id in itertools.count(10):
        address = master.fastscan(known=(VENDOR, PRODUCT, None, None))
        if address is None:
            # a step's answer later than the 10 ms window (a loaded host) spoils a scan, as lss_find's rule says:
            # the scan is repeated while non-configured slaves still answer, a few times at most
            if master.identify_non_configured() == 0:
                break
            spoiled += 1
            assert spoiled <= SPOILED_SCANS, f"{spoiled} scans in a row found none of the slaves that still answer"
            continue
        spoiled = 0
        found.append(address.serial)
        assert master.configure_node_id(node_id).error == 0
        slave = next(s for s in lss_bus.slaves if s.address()[3] == address.serial)
        lss_bus.node_ids[lss_bus.slaves.index(slave)] = slave.pending_node_id  # NMT reset communication
        master.switch_global(LssState.WAITING)
    elapsed = time.perf_counter() - start
    assert sorted(found) == list(range(1000, 1008))
    print(f"\nfastscan, eight slaves, vendor and product known: {elapsed:.2f} s, {master.steps} frames")
    assert elapsed < 5.0, f"eight slaves took {elapsed:.2f} s ({master.steps} frames)"


@pytest.mark.parametrize("lss_bus", [(2, 0.015)], indirect=True)
def test_a_scan_whose_answers_come_after_the_window_widens_it_and_finds_every_slave(lss_bus, monkeypatch):
    """Answers 15 ms after each request, a 10 ms window: every fastscan is spoiled until the scan has doubled the
    window, then both are found (CI, stop 49: eight slaves under load, three spoiled scans in a row, and 'lss scan'
    exited 69; without the widening this finds none). The late
    answers are looked for ten windows here, not two: a loaded CI host delays this test's own answer timers too, and
    the test is about the widening, not the look-out."""
    monkeypatch.setattr(lss_find, "LATE_WINDOWS", 10)
    result = scan_unconfigured(lss_bus.master, (VENDOR, PRODUCT, None, None))
    assert result.widened_to_s is not None
    assert 0.015 < result.widened_to_s <= WIDEST_WINDOW * RESPONSE_S
    assert lss_bus.master.response_s == RESPONSE_S, "the scan gives the window back"
    found = sorted(address.serial for address in result.devices)
    # a loaded host also delays this test's answer timers past a widened window (seen in CI, where one late step
    # of ~70 spoils a fastscan): then the list may be short, but never without saying so
    assert found == [1000, 1001] or result.unresolved, found


def test_selective_switch_inquiry_and_configuration(lss_bus):
    master, slave = lss_bus.master, lss_bus.slaves[0]
    assert not master.switch_selective(LssAddress(VENDOR, PRODUCT, REVISION, 999))  # someone else's serial
    assert master.switch_selective(LssAddress(VENDOR, PRODUCT, REVISION, 1000))
    assert master.inquire_address() == LssAddress(VENDOR, PRODUCT, REVISION, 1000)
    assert master.inquire_node_id() == UNCONFIGURED_NODE_ID
    assert master.configure_node_id(0).error == 1  # 0 and 128..254 are out of range
    assert master.configure_node_id(128).error == 1
    assert master.configure_node_id(5).error == 0
    assert slave.pending_node_id == 5
    assert master.configure_bit_timing(5).error == 1  # index 5 is reserved in table 0
    assert master.configure_bit_timing(3).error == 0  # 250 kbit/s
    assert master.store_configuration().error == 0


@pytest.mark.parametrize("lss_bus", [3], indirect=True)
def test_identify_by_ranges_and_non_configured(lss_bus):
    master = lss_bus.master
    low, high = LssAddress(VENDOR, PRODUCT, REVISION, 1001), LssAddress(VENDOR, PRODUCT, REVISION, 1002)
    assert master.identify_remote(low, high) == 2
    assert master.identify_non_configured() == 3
    lss_bus.node_ids[0] = 7
    assert master.identify_non_configured() == 2


def test_configuration_services_need_configuration_state(lss_bus):
    assert lss_bus.master.configure_node_id(5) is None  # waiting state: no answer
    assert lss_bus.master.inquire("serial") is None


@pytest.fixture
def wdga_twin(rig):
    node, client = rig.boot(load_profile("wachendorff-wdga-mt").profile)
    return rig, node, client


def test_wdga_twin_lss_selective_and_inquiry(wdga_twin):
    rig, node, client = wdga_twin
    master = LssMaster(lambda cob, data: rig.network.send_message(cob, data), rig.log, 0.2)
    identity = LssAddress(*(int.from_bytes(client.sdo.upload(0x1018, sub), "little") for sub in range(1, 5)))
    assert master.switch_selective(identity)
    assert master.inquire_address() == identity
    assert master.inquire_node_id() == node.node_id
    master.switch_global(LssState.WAITING)
    assert master.inquire_node_id() is None  # waiting state: inquiry is not answered


# -- one frame time between an answer and the next request ------------------------------------------------------
def _answer_at(log: FrameLog, timestamp: float) -> None:
    log.on_message_received(can.Message(arbitration_id=SLAVE_COB_ID, data=bytes(8), is_extended_id=False,
                                         timestamp=timestamp, is_rx=True))


def test_a_request_waits_only_what_is_left_of_one_frame_time_after_an_answer(monkeypatch):
    """Counted from the answer's timestamp: a fresh answer costs the rest of a frame time, an older one nothing; a
    timestamp on an adapter's own clock (not the host's) counts as just arrived."""
    log = FrameLog()
    waits: list[float] = []
    master = LssMaster(lambda cob_id, data: None, log, RESPONSE_S)
    monkeypatch.setattr(lss_master.time, "sleep", waits.append)  # what it would wait, without waiting
    assert master.frame_s == FRAME_S == pytest.approx(0.001)  # one 8-byte frame at 125 kbit/s
    master.request(0x5E)
    assert waits == []  # no answer yet
    _answer_at(log, time.time())
    master.request(0x5E)
    assert len(waits) == 1
    assert 0 < waits[0] <= FRAME_S
    master.request(0x5E)
    assert len(waits) == 1  # no answer since the last request
    _answer_at(log, time.time() - 0.005)
    master.request(0x5E)
    assert len(waits) == 1  # five frame times ago: nothing left to wait
    _answer_at(log, 12.5)  # an adapter's clock
    master.request(0x5E)
    assert waits[1:] == [FRAME_S]
    assert LssMaster(lambda cob_id, data: None, log, RESPONSE_S, bitrate=1_000_000).frame_s == FRAME_BITS / 1e6


def test_no_request_follows_an_answer_closer_than_one_frame_time(lss_bus):
    """On a simulated bus the answer arrives at once: the master keeps the frame time a wire would take."""
    master = lss_bus.master
    assert master.switch_selective(LssAddress(VENDOR, PRODUCT, REVISION, 1000))
    assert master.inquire_address() == LssAddress(VENDOR, PRODUCT, REVISION, 1000)
    assert master.configure_node_id(5).error == 0
    answered, gaps = None, []
    for msg in master.frames.last(100):
        if msg.is_rx:
            answered = msg.timestamp
        elif answered is not None:
            gaps.append(msg.timestamp - answered)
            answered = None
    assert len(gaps) == 5  # inquiries after the selective answer and each other, the configure after the last
    assert min(gaps) >= master.frame_s - 1e-6, gaps
