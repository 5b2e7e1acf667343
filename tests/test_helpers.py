"""Small library helpers the suites lean on: FrameLog waits, raw SDO frames, interval statistics,
parameter picking and the simulator's NVM file."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import can
import pytest

from encoder_conformance.dut.link.frames import FrameLog, format_frames
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.dut.store.changeable import STORE_GROUPS, changeable_parameter
from encoder_conformance.models.timing import interval_stats
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.schema import HeartbeatTolerance
from encoder_conformance.sim.engine.nvm import NonVolatileMemory

MINIMAL = Path(__file__).resolve().parent / "data" / "profiles" / "minimal-encoder.yaml"


def msg(cob_id: int, data: bytes = b"", rx: bool = True) -> can.Message:
    return can.Message(arbitration_id=cob_id, data=data, is_extended_id=False, is_rx=rx, timestamp=time.time())


# -- FrameLog ---------------------------------------------------------------------------------------


def test_wait_for_sees_only_frames_after_the_mark():
    """wait_for ignores frames before the mark and returns the first match after it."""
    log = FrameLog()
    log.on_message_received(msg(0x705, b"\x00"))
    mark = log.mark()
    log.on_message_received(msg(0x185, b"\x01"))
    log.on_message_received(msg(0x705, b"\x7f"))
    found = log.wait_for(lambda m: m.arbitration_id == 0x705, 1.0, mark)
    assert found is not None
    assert bytes(found.data) == b"\x7f"
    assert [m.arbitration_id for m in log.since(mark)] == [0x185, 0x705]


def test_wait_count_returns_when_frames_arrive_from_another_thread():
    """wait_count wakes up as frames arrive on another thread and returns exactly ``count``."""
    log = FrameLog()
    mark = log.mark()

    def producer() -> None:
        for n in range(6):
            log.on_message_received(msg(0x700 + n % 2, bytes([n])))

    thread = threading.Thread(target=producer)
    thread.start()
    hits = log.wait_count(lambda m: m.arbitration_id == 0x700, 3, 2.0, mark)
    thread.join()
    assert [m.data[0] for m in hits] == [0, 2, 4]


def test_wait_for_times_out_with_none():
    """Without a matching frame wait_for returns None after (not before) the timeout."""
    log = FrameLog()
    start = time.monotonic()
    assert log.wait_for(lambda m: True, 0.05) is None
    assert time.monotonic() - start >= 0.05


def test_record_sent_marks_tester_frames_and_forwards_to_listeners():
    """Tester frames are logged as Tx; added listeners see every frame."""
    log = FrameLog()
    seen: list[can.Message] = []

    class Collector(can.Listener):
        def on_message_received(self, msg: can.Message) -> None:
            seen.append(msg)

    collector = Collector()
    log.add_listener(collector)
    log.record_sent(msg(0x605, bytes(8), rx=True))
    log.remove_listener(collector)
    log.on_message_received(msg(0x585, bytes(8)))
    assert len(seen) == 1
    sent = log.last(2)[0]
    assert not sent.is_rx
    assert " Tx 605 [8] 00 00 00 00 00 00 00 00" in format_frames([sent])


def test_log_is_bounded():
    """The log keeps the newest ``keep`` frames; marks stay valid."""
    log = FrameLog(keep=3)
    mark = log.mark()
    for n in range(5):
        log.on_message_received(msg(0x100 + n))
    assert [m.arbitration_id for m in log.since(mark)] == [0x102, 0x103, 0x104]


# -- raw SDO frames ---------------------------------------------------------------------------------


def test_request_builders():
    """Upload and expedited download requests are byte-exact."""
    assert sdo_frames.upload_request(0x1018, 1) == bytes.fromhex("40 18 10 01 00 00 00 00")
    assert sdo_frames.expedited_download_request(0x1017, 0, b"\xe8\x03") == bytes.fromhex("2B 17 10 00 E8 03 00 00")
    assert sdo_frames.expedited_download_request(0x6000, 0, b"\x04") == bytes.fromhex("2F 00 60 00 04 00 00 00")
    with pytest.raises(ValueError):
        sdo_frames.expedited_download_request(0x1008, 0, b"12345")


def test_response_parser():
    """SdoResponse decodes abort codes, expedited sizes and segmented sizes."""
    abort = sdo_frames.SdoResponse(bytes.fromhex("80 00 10 00 02 00 01 06"))
    assert abort.is_abort
    assert abort.abort_code == 0x06010002
    assert (abort.index, abort.sub) == (0x1000, 0)
    assert "06010002h" in abort.describe()
    expedited = sdo_frames.SdoResponse(bytes.fromhex("4B 17 10 00 E8 03 00 00"))
    assert expedited.expedited_size == 2
    assert expedited.abort_code is None
    segmented = sdo_frames.SdoResponse(bytes.fromhex("41 08 10 00 0A 00 00 00"))
    assert segmented.segmented_size == 10
    assert segmented.expedited_size is None


def test_abort_name():
    """Abort codes are shown with their CiA 301 text; unknown codes say so."""
    assert sdo_frames.abort_name(0x06020000).startswith("06020000h (")
    assert "not a CiA 301 abort code" in sdo_frames.abort_name(0x12345678)


# -- timing ------------------------------------------------------------------------------------------


def test_interval_stats():
    """Intervals in ms from timestamps in s; mean, worst error and the intervals outside a tolerance."""
    stats = interval_stats([0.0, 0.050, 0.101, 0.150, 0.210], 50)
    assert stats.count == 4
    assert stats.intervals_ms == pytest.approx((50, 51, 49, 60))
    assert stats.mean_ms == pytest.approx(52.5)
    assert stats.worst_error_ms == pytest.approx(10)
    assert [n for n, _ in stats.outside(2.0)] == [3]
    assert stats.csv().splitlines()[0] == "n,interval_ms"


def test_heartbeat_tolerance_is_max_of_abs_and_rel():
    """Per-interval tolerance: max(abs_ms, rel * period)."""
    tolerance = HeartbeatTolerance(abs_ms=2, rel=0.1)
    assert tolerance.allowed_ms(10) == 2
    assert tolerance.allowed_ms(50) == pytest.approx(5)


# -- parameters ----------------------------------------------------------------------------------------


def test_changeable_parameter_prefers_and_respects_limits():
    """The preferred index comes first; 1017h gets a harmless period; the new value stays within max."""
    profile = load_profile(MINIMAL).profile
    found = changeable_parameter(profile, lambda i, e: e.persisted_by in STORE_GROUPS, prefer=(0x1017,))
    assert found is not None
    assert (found.index, found.new_value) == (0x1017, 10 * profile.timing.heartbeat_test_period_ms)
    app = changeable_parameter(profile, lambda i, e: i == 0x6001)
    assert app is None, "6001h default 4096 is already its max: no valid other value"
    assert changeable_parameter(profile, lambda i, e: False) is None


def test_changeable_parameter_skips_node_id_and_bitrate_objects():
    """Objects behind node_id_object / bitrate_object quirks are never chosen."""
    profile = load_profile("wachendorff-wdga-mt").profile
    found = changeable_parameter(profile, lambda i, e: 0x2000 <= i < 0x6000)
    assert found is None or found.index not in (0x2100, 0x2101)


# -- NVM ------------------------------------------------------------------------------------------------


def test_nvm_file_round_trip(tmp_path):
    """Values written to the NVM file are there for a new instance (a power cycle); removals too."""
    path = tmp_path / "sub" / "nvm.json"
    nvm = NonVolatileMemory(path)
    nvm.put_many({(0x1017, 0): 100, (0x1008, 0): "NAME"})
    again = NonVolatileMemory(path)
    assert again.snapshot() == {(0x1017, 0): 100, (0x1008, 0): "NAME"}
    again.remove_many([(0x1017, 0)])
    assert (0x1017, 0) not in NonVolatileMemory(path)
    assert not list(path.parent.glob(".nvm-*")), "temporary files left behind"


def test_nvm_in_memory_writes_no_file(tmp_path):
    """Without a path the NVM lives in memory only."""
    nvm = NonVolatileMemory(None)
    nvm.put_many({(0x6001, 0): 2048})
    assert nvm.get((0x6001, 0)) == 2048
    assert list(tmp_path.iterdir()) == []


def test_quirk_faults_name_known_faults_and_effects():
    from encoder_conformance.profile.quirks import EFFECTS
    from encoder_conformance.sim.fault_catalogue import FAULTS, QUIRK_EFFECT_OF_FAULT, faults_for

    assert set(QUIRK_EFFECT_OF_FAULT) <= set(FAULTS)
    assert set(QUIRK_EFFECT_OF_FAULT.values()) <= set(EFFECTS)
    assert faults_for(EFFECTS) == sorted(FAULTS)
    general = faults_for(())
    assert "reload_not_immediate" not in general
    assert "wrong_vendor_id" in general


def test_every_suite_module_is_the_target_of_a_fault_group():
    """A new suite module needs faults made for it (sim/fault_catalogue.py FAULT_GROUPS), and targets must exist; the
    goods-in module runs only in acceptances, where tests/test_coverage_verdict.py fails it with
    device_error_at_start."""
    from pathlib import Path

    from encoder_conformance.plugin.acceptance import GOODS_IN_MODULE
    from encoder_conformance.sim.fault_catalogue import TARGET_MODULES

    suites = {p.stem for p in (Path(__file__).resolve().parents[1] / "suites").glob("test_*.py")} - {GOODS_IN_MODULE}
    targets = {module for modules in TARGET_MODULES.values() for module in modules}
    assert suites - targets == set(), "suite modules no fault is made for"
    assert targets - suites == set(), "fault targets that are not suite modules"
