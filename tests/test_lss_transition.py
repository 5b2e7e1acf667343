"""The LSS states by transition (``LssDevice.transition``, issue 41): each state reached by one call and seen by what it
answers; the frames it sends are those the suites sent by hand before (switch state selective where the device has
it), so their verdicts stay the same."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest

from encoder_conformance.cia.cia305 import LssState
from encoder_conformance.dut.lss import LssAddress, LssDevice

ADDRESS = LssAddress(0x5A, 1, 2, 1000)


class FakeMaster:
    """An LSS master that records the services asked of it and answers as told."""

    def __init__(self, selective: bool = True, inquired: int | None = 3) -> None:
        self.calls: list[tuple[str, Any]] = []
        self._selective = selective
        self._inquired = inquired

    def switch_selective(self, address: LssAddress) -> bool:
        self.calls.append(("switch_selective", address))
        return self._selective

    def switch_global(self, state: LssState) -> None:
        self.calls.append(("switch_global", state))

    def inquire_node_id(self) -> int | None:
        self.calls.append(("inquire_node_id", None))
        return self._inquired


def _device(services: list[str], master: FakeMaster) -> LssDevice:
    frames = SimpleNamespace(mark=lambda: None, since=lambda *args: [])
    dut = SimpleNamespace(profile=SimpleNamespace(capabilities=SimpleNamespace(lss=services)), frames=frames,
                          node_id=3)
    return LssDevice(dut, master, ADDRESS, None)  # type: ignore[arg-type]  # why: fakes of the link and the master


def test_configuration_by_switch_selective_seen_by_its_answer():
    master = FakeMaster()
    _device(["switch_global", "switch_selective", "inquire_node_id"], master).transition("configuration")
    assert master.calls == [("switch_selective", ADDRESS)]  # no inquire: the 44h answer shows the state


def test_configuration_not_reached_names_the_heartbeat_state():
    device = _device(["switch_global", "switch_selective"], FakeMaster(selective=False))
    with pytest.raises(AssertionError, match=r"no answer \(44h\); the heartbeat at node-ID 3 reports"):
        device.transition("configuration")


def test_configuration_by_switch_global_seen_by_an_inquire():
    master = FakeMaster()
    _device(["switch_global", "inquire_node_id"], master).transition("configuration")
    assert master.calls == [("switch_global", LssState.CONFIGURATION), ("inquire_node_id", None)]
    with pytest.raises(AssertionError, match="inquire node-ID unanswered"):
        _device(["switch_global", "inquire_node_id"], FakeMaster(inquired=None)).transition("configuration")


def test_waiting_by_switch_global_0_and_unknown_states_refused():
    master = FakeMaster()
    device = _device(["switch_global", "switch_selective"], master)
    device.transition("waiting")
    assert master.calls == [("switch_global", LssState.WAITING)]
    with pytest.raises(ValueError, match="unknown LSS state 'unconfigured'"):
        device.transition("unconfigured")
