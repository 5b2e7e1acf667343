"""The parts of the device custody without a bus: write order, snapshot file, store watch, store commands,
station file and power switches."""

from __future__ import annotations

import json
import sys

import can
import pytest

from encoder_conformance.cia301 import LOAD, SAVE
from encoder_conformance.dut.persist import StoreCommand, store_commands_for
from encoder_conformance.dut.power import BenchPower, PowerSwitchError, ShellPowerSwitch
from encoder_conformance.dut.snapshot import Snapshot, SnapshotEntry, custody_keys
from encoder_conformance.dut.store_watch import StoreWatch
from encoder_conformance.dut.write_plan import plan_writes
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.station import StationError, load_station


def u32(value: int) -> bytes:
    return value.to_bytes(4, "little")


def u8(value: int) -> bytes:
    return value.to_bytes(1, "little")


@pytest.fixture(scope="module")
def wdga():
    return load_profile("wachendorff-wdga-mt").profile


@pytest.fixture(scope="module")
def siko():
    return load_profile("siko-wx58m-1212-mt").profile


def test_pdo_mapping_is_written_the_cia301_way(wdga):
    """Mapping changes: COB-ID invalid first, count 0, entries, count, then the COB-ID (CiA 301 §7.5.2.36)."""
    current = {(0x1A00, 0): u8(1), (0x1A00, 1): u32(0x60040020), (0x1800, 1): u32(0x40000185)}
    targets = {(0x1A00, 0): u8(2), (0x1A00, 1): u32(0x60040020), (0x1A00, 2): u32(0x60300110)}
    steps = [(s.key, s.value, s.temporary) for s in plan_writes(wdga, targets, current)]
    assert steps == [
        ((0x1800, 1), u32(0xC0000185), True),
        ((0x1A00, 0), u8(0), True),
        ((0x1A00, 1), u32(0x60040020), False),
        ((0x1A00, 2), u32(0x60300110), False),
        ((0x1A00, 0), u8(2), False),
        ((0x1800, 1), u32(0x40000185), False),
    ]


def test_pdo_parameters_change_while_the_pdo_is_invalid(wdga):
    """An event timer of a valid TPDO is written between invalidating and re-validating its COB-ID."""
    current = {(0x1800, 1): u32(0x40000185), (0x1800, 5): b"\x00\x00"}
    steps = plan_writes(wdga, {(0x1800, 5): b"\x64\x00"}, current)
    assert [s.key for s in steps] == [(0x1800, 1), (0x1800, 5), (0x1800, 1)]
    assert steps[0].value == u32(0xC0000185)
    assert steps[-1].value == u32(0x40000185)


def test_an_invalid_pdo_needs_no_extra_steps(wdga):
    current = {(0x1801, 1): u32(0xC0000285), (0x1801, 2): u8(1)}
    steps = plan_writes(wdga, {(0x1801, 2): u8(3)}, current)
    assert [(s.key, s.value) for s in steps] == [((0x1801, 2), u8(3))]


def test_scaling_gate_opened_for_gated_writes_and_put_back(siko):
    """SIKO refuses 6001h unless 6000h bit 2 is set (quirk writes_need_scaling_bit): set, write, put back."""
    current = {(0x6000, 0): b"\x00\x00", (0x6001, 0): u32(4096)}
    steps = plan_writes(siko, {(0x6001, 0): u32(8192)}, current)
    assert [(s.key, s.value) for s in steps] == [
        ((0x6000, 0), b"\x04\x00"), ((0x6001, 0), u32(8192)), ((0x6000, 0), b"\x00\x00")]


def test_other_values_in_index_order(wdga):
    steps = plan_writes(wdga, {(0x6200, 0): b"\x14\x00", (0x1017, 0): b"\xe8\x03"}, {})
    assert [s.key for s in steps] == [(0x1017, 0), (0x6200, 0)]


def test_custody_keys_leave_out_commands_and_changing_values(wdga):
    keys = custody_keys(wdga)
    assert (0x1017, 0) in keys
    assert not any(index in (0x1010, 0x1011) for index, _ in keys)
    assert (0x1003, 0) not in keys  # error history: changes by itself
    assert (0x1018, 1) not in keys  # read-only


def test_snapshot_file_round_trip(tmp_path):
    snapshot = Snapshot("p", "abc", 5, {"serial number (1018h.4)": "7"}, True, 0x05,
                        [SnapshotEntry(0x1017, 0, "Producer heartbeat time", "store_comm", "e803", "0000")])
    path = snapshot.save(tmp_path / "s.json")
    loaded = Snapshot.load(path)
    assert loaded == snapshot
    assert loaded.entries[0].target_found() == b"\xe8\x03"
    assert loaded.entries[0].target_stored() == b"\x00\x00"
    assert loaded.serial == "7"


@pytest.mark.parametrize(("content", "message"), [
    ("{not json", "cannot read the snapshot"),
    ('{"format": "something else"}', "not a device snapshot"),
    ('{"format": "encoder-conformance device snapshot 1", "entries": [{"index": 1}]}', "malformed snapshot"),
])
def test_snapshot_file_errors_name_the_file(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content, encoding="utf-8")
    with pytest.raises(ValueError, match=message) as raised:
        Snapshot.load(path)
    assert str(path) in str(raised.value)


def _download(node_id: int, index: int, sub: int, data: bytes) -> can.Message:
    payload = bytes([0x23, index & 0xFF, index >> 8, sub]) + data.ljust(4, b"\x00")
    return can.Message(arbitration_id=0x600 + node_id, data=payload, is_rx=False)


def test_store_watch_counts_what_changes_the_memory(wdga):
    watch = StoreWatch(wdga, 5)
    for msg in (_download(5, 0x1010, 1, SAVE), _download(5, 0x1011, 1, LOAD),
                _download(5, 0x2120, 1, u32(7)),  # persisted_by auto: stored by the device itself
                _download(5, 0x1017, 0, b"\x32\x00"),  # RAM only
                _download(6, 0x1010, 1, SAVE)):  # another node
        watch.on_message_received(msg)
    reply = can.Message(arbitration_id=0x585, data=b"\x60\x10\x10\x01\x00\x00\x00\x00", is_rx=True)
    watch.on_message_received(reply)
    assert watch.total == 3
    watch.restoring = True
    watch.on_message_received(_download(5, 0x1010, 2, SAVE))
    assert (watch.total, watch.total_by_restore) == (3, 1)


def test_store_commands_cover_each_group_once(wdga):
    commands = store_commands_for(wdga, [(0x1017, 0), (0x1800, 5), (0x6200, 0), (0x2120, 1)])
    assert [(c.index, c.sub) for c in commands] == [(0x1010, 2), (0x1010, 3)]  # 2120h stores itself


def test_rebooting_store_command_goes_last():
    posital = load_profile("fraba-posital-awc58-c2-mt").profile
    manufacturer = [k for k in custody_keys(posital) if posital.entry(*k).persisted_by == "manufacturer_store"]
    commands = store_commands_for(posital, manufacturer)
    assert commands == [StoreCommand(0x2300, 0, bytes([0x55, 0xAA, 0xAA, 0x55]), True, "store-via-2300h-reboots")]
    assert commands[0].request()[0] == 0x22  # the manual's frame: download, size not indicated


def test_station_file_errors_name_file_and_key(tmp_path):
    path = tmp_path / "bench.yaml"
    path.write_text("station: b3\ncan: {interface: pcan, chanel: PCAN_USBBUS1}\nnode_id: 300\n", encoding="utf-8")
    with pytest.raises(StationError) as raised:
        load_station(path)
    text = str(raised.value)
    assert f"{path}: can.chanel" in text
    assert f"{path}: node_id" in text


def test_station_file_with_power_commands(tmp_path):
    path = tmp_path / "bench.yaml"
    path.write_text("station: b3\npower: {off_command: 'relay 3 off', on_command: 'relay 3 on', off_time_s: 0.5}\n",
                    encoding="utf-8")
    station = load_station(path)
    assert station.power.off_command == "relay 3 off"
    assert station.power.off_time_s == 0.5


def test_shell_power_switch_runs_both_commands(tmp_path):
    marker = tmp_path / "log"
    python = sys.executable
    switch = ShellPowerSwitch(f"{python} -c \"open(r'{marker}', 'a').write('off ')\"",
                              f"{python} -c \"open(r'{marker}', 'a').write('on')\"", off_time_s=0)
    BenchPower(switch).cycle()
    assert marker.read_text() == "off on"


def test_failing_power_command_names_option_and_output():
    switch = ShellPowerSwitch(f"{sys.executable} -c \"import sys; sys.exit('relay board not found')\"", "true")
    with pytest.raises(PowerSwitchError, match=r"--power-off-cmd .* exit status 1: relay board not found"):
        switch.off()


def test_snapshot_json_is_readable_by_people(tmp_path):
    snapshot = Snapshot("p", "abc", 5, {}, False, None, [SnapshotEntry(0x6200, 0, "Cyclic timer", "store_app",
                                                                       None, "1400")])
    raw = json.loads(snapshot.save(tmp_path / "s.json").read_text(encoding="utf-8"))
    assert raw["entries"][0] == {"index": 0x6200, "sub": 0, "name": "Cyclic timer", "persisted_by": "store_app",
                                 "found": None, "stored": "1400"}
