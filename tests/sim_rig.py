"""A simulator host and a canopen tester on one private virtual channel, for the simulator's self-tests.

Every wait is on a frame (FrameLog.wait_for) or on a scheduler sentinel, never a fixed sleep.
"""

from __future__ import annotations

import itertools
import threading
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import can
import canopen
import pytest

from encoder_conformance.config.bus import BusConfig
from encoder_conformance.dut.link.frames import FrameLog, Mark
from encoder_conformance.dut.link.tracing_bus import TracingBus
from encoder_conformance.profile.quirk_effects import SilentUntilBusTraffic
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.faults import FaultSet
from encoder_conformance.sim.engine.host import SimulatorHost
from encoder_conformance.sim.engine.node import SimulatedNode

REPO = Path(__file__).resolve().parents[1]
MINIMAL = REPO / "tests" / "data" / "profiles" / "minimal-encoder.yaml"
WAIT_S = 2.0  # upper bound for any expected frame; tests go on as soon as it arrives

_channels = itertools.count()


@dataclass
class Rig:
    """One simulator host and one tester (canopen Network + FrameLog) on a private virtual channel."""

    host: SimulatorHost
    network: canopen.Network
    log: FrameLog
    tmp_path: Path

    def add(self, profile: DeviceProfile, faults: tuple[str, ...] = ()) -> SimulatedNode:
        """A node of ``profile`` on the bus, not yet powered, with its NVM file in tmp_path."""
        return self.host.add_node(profile, nvm_path=self.tmp_path / "nvm.json", faults=FaultSet(faults),
                                  power_on=False)

    def boot(
        self, profile: DeviceProfile, node_id: int | None = None, faults: tuple[str, ...] = (),
        nvm_name: str | None = None,
    ) -> tuple[SimulatedNode, canopen.RemoteNode]:
        """Add, power and wait for the boot-up of a node (waking it if it waits for bus traffic)."""
        nvm = self.tmp_path / (nvm_name or f"nvm-{profile.id}.json")
        node = self.host.add_node(profile, node_id, nvm, FaultSet(faults), power_on=False)
        mark = self.log.mark()
        node.power_on()
        if profile.has_effect(SilentUntilBusTraffic):
            self.send(0x80)
        assert self.wait_bootup(node.node_id, mark) is not None, "no boot-up"
        return node, self.client(node.node_id)

    def client(self, node_id: int) -> canopen.RemoteNode:
        remote = canopen.RemoteNode(node_id, canopen.ObjectDictionary())
        self.network.add_node(remote)
        remote.sdo.RESPONSE_TIMEOUT = WAIT_S
        return remote

    def send(self, cob_id: int, data: bytes = b"", remote: bool = False) -> Mark:
        mark = self.log.mark()
        self.network.send_message(cob_id, data, remote=remote)
        return mark

    def nmt(self, command: int, node_id: int) -> Mark:
        return self.send(0x000, bytes([command, node_id]))

    def frame(self, cob_id: int, after: Mark, timeout: float = WAIT_S) -> can.Message | None:
        return self.log.wait_for(lambda m: m.is_rx and m.arbitration_id == cob_id, timeout, after)

    def frames(self, cob_id: int, after: Mark) -> list[can.Message]:
        return self.log.since(after, lambda m: m.is_rx and m.arbitration_id == cob_id)

    def wait_bootup(self, node_id: int, after: Mark, timeout: float = WAIT_S) -> can.Message | None:
        return self.log.wait_for(
            lambda m: m.is_rx and m.arbitration_id == 0x700 + node_id and bytes(m.data) == b"\x00", timeout, after
        )

    def power_on(self, node: SimulatedNode) -> can.Message | None:
        """Power the node and return its boot-up frame (None if it stays silent)."""
        mark = self.log.mark()
        node.power_on()
        return self.wait_bootup(node.node_id, mark)

    def raw_sdo(self, node_id: int, request: bytes) -> can.Message | None:
        """Send one raw SDO request; the node's response frame or None."""
        return self.frame(0x580 + node_id, self.send(0x600 + node_id, request))

    def scheduler_drained(self, delay_s: float) -> bool:
        """True once the simulator's scheduler has run everything due within ``delay_s``."""
        done = threading.Event()
        self.host.scheduler.call_later(delay_s, done.set)
        return done.wait(WAIT_S + delay_s)


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    channel = f"selftest-{uuid.uuid4().hex[:8]}-{next(_channels)}"
    host = SimulatorHost(channel=channel)
    log = FrameLog()
    network = canopen.Network(TracingBus(can.Bus(interface="virtual", channel=channel), log))
    network.NOTIFIER_CYCLE = 0.02  # short receive timeout: disconnect() returns at once
    network.listeners.append(log)
    network.connect()
    yield Rig(host, network, log, tmp_path)
    network.disconnect()
    host.shutdown()


@dataclass
class Twin:
    """A twin served on a private virtual channel, and the bus settings a tool reaches it with."""

    host: SimulatorHost
    node: SimulatedNode
    bus: BusConfig


@contextmanager
def twin_of(profile: DeviceProfile, node_id: int | None = None, faults: tuple[str, ...] = ()) -> Iterator[Twin]:
    channel = f"probe-{uuid.uuid4().hex[:8]}"
    host = SimulatorHost(channel=channel)
    try:
        node = host.add_node(profile, node_id or profile.bus.node_id, faults=FaultSet(faults))
        yield Twin(host, node, BusConfig({"interface": "virtual", "channel": channel}))
    finally:
        host.shutdown()
