"""Custody of entries that alias (a write to one changes the other): the order of writes that works, the reset
node that gives back what no order can, and the twin variant that plays the WDGA's open reading (6200h and
1800h sub 5 one value, open reading ``cyclic-timer-vs-event-timer``) against a custody driven directly, in an
accept and in a full run (~50 s in all). And a memory that had no valid stored data at the start (EMCY 5000h
after the boot-up) and has after the run's store: reported as not as found (``dut/store/boot_memory.py``)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from encoder_conformance.cia.cia301 import SAVE
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.custody.aliased_values import AliasRepair, entries_that_may_alias, write_order
from encoder_conformance.dut.custody.custody import Custody
from encoder_conformance.dut.store.store_watch import StoreWatch
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.schema import DeviceProfile
from tests import sim_rig
from tests.sim_rig import Rig

rig = sim_rig.rig  # the shared simulator fixture

REPO = Path(__file__).resolve().parents[1]
VARIANT = "cyclic_timer_aliases_event_timer"
CYCLIC, EVENT = (0x6200, 0), (0x1800, 5)
A, B, C = (0x2000, 0), (0x2001, 0), (0x2002, 0)


def u16(value: int) -> bytes:
    return value.to_bytes(2, "little")


class OneWayAlias:
    """A fake device where writing A also sets B (not the other way round)."""

    def __init__(self, values: dict[tuple[int, int], bytes]) -> None:
        self.values = dict(values)
        self.writes: list[tuple[int, int]] = []

    def read(self, keys: list[tuple[int, int]]) -> dict[tuple[int, int], bytes | None]:
        return {k: self.values[k] for k in keys}

    def write(self, key: tuple[int, int], value: bytes) -> None:
        self.writes.append(key)
        self.values[key] = value
        if key == A:
            self.values[B] = value


def test_write_order_puts_the_changing_entry_first():
    """Writing A changes B: A first; entries that change each other with different targets: no order."""
    targets = {A: u16(1), B: u16(2), C: u16(3)}
    assert write_order([A, B, C], {(A, B)}, targets) == [A, B, C]
    assert write_order([B, A], {(A, B)}, targets) == [A, B]
    assert write_order([A, B], {(A, B), (B, A)}, targets) is None
    assert write_order([A, B], {(A, B), (B, A)}, {A: u16(1), B: u16(1)}) == [A, B], "same value: any order"


def test_one_way_alias_found_and_written_in_order():
    """B was written before A (index order) and A's write changed it: read back, found, written A then B."""
    device = OneWayAlias({A: u16(1), B: u16(1)})  # the write-back's result: A = 1 also set B
    targets = {A: u16(1), B: u16(2)}
    outcome = AliasRepair(device.read, device.write).repair(targets, device.read([A, B]), [B, A])
    assert (A, B) in outcome.edges
    assert (B, A) not in outcome.edges
    assert not outcome.conflicting
    assert device.values == targets
    assert device.writes[-2:] == [A, B]


def test_entries_that_may_alias_come_from_the_profile():
    """The WDGA's manual leaves 6200h and 1800h sub 5 unrelated; a CiA 406 profile says nothing open."""
    assert entries_that_may_alias(load_profile("wachendorff-wdga-mt").profile) == {CYCLIC, EVENT}
    assert entries_that_may_alias(load_profile("cia406-c2-st").profile) == frozenset()


def _fast(profile_id: str) -> DeviceProfile:
    profile = load_profile(profile_id).profile
    return profile.model_copy(update={"simulator": profile.simulator.model_copy(update={"bootup_delay_ms": 5})})


def _custody(rig: Rig, faults: tuple[str, ...], tmp_path: Path, read_stored: bool) -> tuple[DeviceUnderTest, Custody]:
    """A WDGA twin fresh from the factory (6200h = 1, 1800h sub 5 = 0) taken into custody."""
    profile = _fast("wachendorff-wdga-mt")
    node, _ = rig.boot(profile, faults=faults)
    dut = DeviceUnderTest(rig.network, rig.log, profile, node.node_id)
    watch = StoreWatch(profile, dut.node_id)
    rig.log.add_listener(watch)
    custody = Custody(dut, tmp_path / "device-snapshot.json", watch)
    custody.take("sha", read_stored=read_stored)
    assert (dut.read(*CYCLIC), dut.read(*EVENT)) == (u16(1), u16(0))
    return dut, custody


def _event_timer_test(dut: DeviceUnderTest) -> None:
    """What the heartbeat capture does: TPDO1's event timer 50 ms, put back to 0 (the aliased twin: 6200h = 0)."""
    dut.write(*EVENT, u16(50))
    dut.write(*EVENT, u16(0))


def test_aliased_timers_given_back_by_reset_node(rig, tmp_path):
    """One value behind 6200h and 1800h sub 5, found 1 and 0 (their stored values): no order of writes gives them
    back, a reset node does, and the read-back after it shows both as found."""
    dut, custody = _custody(rig, (VARIANT,), tmp_path, read_stored=True)
    _event_timer_test(dut)
    assert dut.read(*CYCLIC) == u16(0), "the variant: the event timer's write set the cyclic timer"
    record = custody.give_back(30)
    assert record.ok, record.failures
    assert any(line.startswith("NMT reset node: writing 1800h.05 or 6200h.00 changes the other")
               for line in record.written), record.written
    assert (dut.read(*CYCLIC), dut.read(*EVENT)) == (u16(1), u16(0))


def test_aliased_timers_without_stored_values_are_reported(rig, tmp_path):
    """An acceptance's snapshot has no stored values: no reset, and the failure says why."""
    dut, custody = _custody(rig, (VARIANT,), tmp_path, read_stored=False)
    _event_timer_test(dut)
    record = custody.give_back(30)
    assert not record.ok
    assert "no order of writes gives back 1800h.05, 6200h.00 as found" in record.failures[0]
    assert "an acceptance sends no reset" in record.failures[0]
    assert not any(line.startswith("NMT reset node") for line in record.written)


def test_independent_timers_given_back_without_reset(rig, tmp_path):
    """The default twin (two values): the cyclic timer a test changed is written back, nothing else."""
    dut, custody = _custody(rig, (), tmp_path, read_stored=True)
    dut.write(*CYCLIC, u16(20))
    record = custody.give_back(30)
    assert record.ok, record.failures
    assert record.written == ["6200h.00 = 01 00"]
    assert (dut.read(*CYCLIC), dut.read(*EVENT)) == (u16(1), u16(0))


def _command(tmp_path: Path, command: str, *args: str) -> tuple[int, dict]:
    """An accept or run against the WDGA twin: exit code and device-restore.json."""
    folder = tmp_path / command
    result = subprocess.run([sys.executable, "-m", "encoder_conformance", command, "--profile", "wachendorff-wdga-mt",
                             "--report-dir", str(folder), *args], cwd=REPO, capture_output=True, text=True,
                            timeout=300)
    restore = folder / "device-restore.json"
    assert restore.exists(), result.stdout[-3000:] + result.stderr[-3000:]
    assert result.returncode == RunExit.PASSED, result.stdout[-3000:] + result.stderr[-3000:]
    return result.returncode, json.loads(restore.read_text(encoding="utf-8"))


@pytest.mark.parametrize("faults", [(), ("--sim-fault", VARIANT)], ids=["two values", "one value"])
def test_accept_leaves_the_timers_alone(tmp_path, faults):
    """An acceptance writes neither timer the manual leaves open (README: it writes nothing it cannot put back)."""
    _, restore = _command(tmp_path, "accept", *faults)
    assert restore["done"]
    assert not restore["failures"]
    assert restore["left_changed"] == []
    assert restore["written"] == []


def test_full_run_with_one_timer_value_gives_the_device_back(tmp_path):
    """A full run against the aliased twin ends PASS with every value as found."""
    _, restore = _command(tmp_path, "run", "--sim-fault", VARIANT)
    assert restore["done"]
    assert not restore["failures"]


# -- a device that had no valid stored data at the start (``boot_memory``) ---------------------------------------

def _without_storage_files(node) -> None:
    """CANopenNode's demo without its storage files: EMCY 5000h after each boot-up while nothing is stored."""
    node.hooks.booted.append(lambda: None if node.nvm.snapshot() else node.raise_emcy(0x5000, 0x01))


@pytest.mark.parametrize("faults", [(), ("device_error_at_start",)], ids=["stores", "error at every start"])
def test_memory_not_as_found_after_a_run_stored_on_an_empty_memory(rig, tmp_path, faults):
    """5000h after the boot-up at the start, a store by the run, none after the give-back's boot-up: the values
    are given back, the memory is not, and the record says so; a device that reports the error at every start
    (whatever it stored) shows nothing of its memory, and no note is made."""
    profile = _fast("wachendorff-wdga-mt")
    node, _ = rig.boot(profile, faults=faults)
    _without_storage_files(node)
    dut = DeviceUnderTest(rig.network, rig.log, profile, node.node_id)
    watch = StoreWatch(profile, dut.node_id)
    rig.log.add_listener(watch)
    custody = Custody(dut, tmp_path / "device-snapshot.json", watch)
    custody.take("sha")
    assert 0x5000 in custody.snapshot.boot_emcy
    dut.write(0x1017, 0, u16(100))
    dut.write(0x1010, 1, SAVE)
    record = custody.give_back(30)
    assert record.ok, record.failures
    if faults:
        assert record.memory is None
    else:
        assert record.memory
        assert "no valid stored parameters when the run began (EMCY 5000h" in record.memory
        assert json.loads((tmp_path / "device-snapshot.json").read_text(encoding="utf-8"))["boot_emcy"] == [0x5000]


def test_aliased_timers_stored_by_the_run_given_back_group_by_group(rig, tmp_path):
    """The run stored the tied value (both 50); stored as delivered they differ (1, 0): written and stored one
    store group at a time (1800h sub 5 with 1010h sub 2, 6200h with sub 3), the memory holds both again."""
    dut, custody = _custody(rig, (VARIANT,), tmp_path, read_stored=True)
    dut.write(*EVENT, u16(50))
    dut.write(0x1010, 1, SAVE)
    record = custody.give_back(30)
    assert record.ok, record.failures
    alone = [line for line in record.written if "stored alone" in line]
    assert [line.split(" =")[0] for line in alone] == ["1800h.05", "6200h.00"]
    assert record.store_commands[-2:] == ["1010h.02 'save'", "1010h.03 'save'"]
    assert (dut.read(*CYCLIC), dut.read(*EVENT)) == (u16(1), u16(0))
    assert dut.nmt.reset_and_reach()
    assert (dut.read(*CYCLIC), dut.read(*EVENT)) == (u16(1), u16(0)), "the memory as delivered"
