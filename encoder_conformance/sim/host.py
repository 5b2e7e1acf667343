"""The simulator host: one CAN bus, one receive thread, one scheduler, any number of nodes.

Nodes on the same host also hear each other (a real bus delivers every frame to every other
node). The host can serve its bus to other processes through python-can-remote.
"""

from __future__ import annotations

import logging
import sys
import threading
from pathlib import Path

import can

from ..profile.model import DeviceProfile
from .faults import FaultSet
from .node import SimulatedNode
from .scheduler import DeadlineScheduler

log = logging.getLogger(__name__)


class SimulatorHost:
    """Owns the bus the simulated nodes sit on."""

    def __init__(self, channel: str, interface: str = "virtual", **bus_kwargs: object) -> None:
        self.channel = channel
        self.bus = can.Bus(interface=interface, channel=channel, **bus_kwargs)
        self.scheduler = DeadlineScheduler()
        self.nodes: list[SimulatedNode] = []
        self._send_lock = threading.Lock()
        self._notifier = can.Notifier(self.bus, [self._dispatch], timeout=0.05)
        self._remote = None

    def add_node(
        self,
        profile: DeviceProfile,
        node_id: int | None = None,
        nvm_path: Path | None = None,
        faults: FaultSet | None = None,
        power_on: bool = True,
    ) -> SimulatedNode:
        node = SimulatedNode(profile, self.scheduler, self._send_from(None), node_id, nvm_path, faults)
        node._send_raw = self._send_from(node)
        self.nodes.append(node)
        if power_on:
            node.power_on()
        return node

    def node(self, node_id: int | None = None) -> SimulatedNode:
        """The node with ``node_id`` (or the only node)."""
        if node_id is None:
            if len(self.nodes) != 1:
                raise LookupError(f"{len(self.nodes)} nodes on the bus; name a node-id")
            return self.nodes[0]
        for node in self.nodes:
            if node.node_id == node_id:
                return node
        raise LookupError(f"no simulated node with node-id {node_id}; have {[n.node_id for n in self.nodes]}")

    def _send_from(self, origin: SimulatedNode | None):
        def send(cob_id: int, data: bytes, extended: bool = False) -> None:
            msg = can.Message(arbitration_id=cob_id, data=data, is_extended_id=extended)
            with self._send_lock:
                try:
                    self.bus.send(msg)
                except can.CanError as exc:
                    log.warning("send failed: %s", exc)
            for other in self.nodes:  # the other nodes on this bus hear it too
                if other is not origin:
                    other.on_frame(msg)

        return send

    def _dispatch(self, msg: can.Message) -> None:
        for node in self.nodes:
            try:
                node.on_frame(msg)
            except Exception:
                log.exception("node %s failed on frame %s", node.node_id, msg)

    def serve_remote(self, host: str = "127.0.0.1", port: int = 0) -> tuple[str, int]:
        """Serve this bus to other processes (python-can-remote); returns the bound address."""
        from can_remote.server import RemoteServer

        logging.getLogger("can_remote").setLevel(logging.WARNING)
        self._remote = RemoteServer(host, port, interface="virtual", channel=self.channel)
        threading.Thread(target=self._remote.serve_forever, name="remote-server", daemon=True).start()
        return host, self._remote.server_port

    def shutdown(self) -> None:
        for node in self.nodes:
            node.power_off()
        self.scheduler.stop()
        self._notifier.stop()
        if self._remote is not None:
            self._remote.shutdown()
        try:
            self.bus.shutdown()
        except Exception as exc:  # pragma: no cover - shutdown must not raise
            print(f"bus shutdown: {exc}", file=sys.stderr)
