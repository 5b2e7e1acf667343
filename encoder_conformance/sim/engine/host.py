"""The simulator host: one CAN bus, frames handled one at a time, one scheduler, any number of nodes.

Frames are handled by a receive thread of the host, or (served to other processes) in the server thread
that received them.

Nodes on the same host also hear each other (a real bus delivers every frame to every other
node). The host can serve its bus to other processes through python-can-remote. A device with
the quirk ``second_node`` (a redundant interface) gets its sibling node through ``add_siblings``.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from queue import Queue
from typing import TYPE_CHECKING, Any, cast

import can
from can.interfaces.virtual import VirtualBus, channels_lock

from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.quirk_effects import SecondNode
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.faults import FaultSet
from encoder_conformance.sim.engine.node import SimulatedNode
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler
from encoder_conformance.sim.engine.virtual_channel import CopyingVirtualBus, open_channel, server_config

if TYPE_CHECKING:
    from can_remote.server import RemoteServer

log = logging.getLogger(__name__)
SERVER_POLL_S = 0.05
NOTED_RECEIVE_LAG_MS = 1.0  # receive lags below this are the normal cost of a frame (not kept)


class _DirectDispatch:
    """Stands in a virtual channel's list of listener queues: ``put`` handles the frame at once."""

    def __init__(self, dispatch: Callable[[can.Message], None]) -> None:
        self._dispatch = dispatch
        self._lock = threading.Lock()

    def put(self, msg: can.Message, block: bool = True, timeout: float | None = None) -> None:
        with self._lock:
            self._dispatch(msg)


class _ClientsSentDirectly(list[Any]):
    """python-can-remote's server's list of connected testers (``RemoteServer.clients``): each tester's bus is
    told, as it joins the list, to send it the frames of the bus at once (``CopyingVirtualBus.send_directly``).
    The server appends each connection's protocol to the list once its bus is open, before it starts serving."""

    def append(self, protocol: Any) -> None:
        bus = getattr(protocol, "bus", None)
        if isinstance(bus, CopyingVirtualBus):
            bus.send_directly(protocol.send_msg)
        super().append(protocol)


class SimulatorHost:
    """Owns the bus the simulated nodes sit on."""

    def __init__(self, channel: str, interface: str = "virtual", **bus_kwargs: Any) -> None:
        self.channel = channel
        # python-can's virtual bus (the default), its frames copied without deepcopy: virtual_channel.py
        self.bus = (open_channel(channel, **bus_kwargs) if interface == "virtual"
                    else can.Bus(interface=interface, channel=channel, **bus_kwargs))
        self.scheduler = DeadlineScheduler()
        self.nodes: list[SimulatedNode] = []
        self._primary_of: dict[int, SimulatedNode] = {}  # id(sibling) -> the node whose quirk added it
        self._send_lock = threading.Lock()
        self._notifier = can.Notifier(self.bus, [self._dispatch], timeout=0.05)
        self._remote: RemoteServer | None = None

    def add_node(
        self,
        profile: DeviceProfile,
        node_id: int | None = None,
        nvm_path: Path | None = None,
        faults: FaultSet | None = None,
        power_on: bool = True,
        serial_number: int | None = None,
        booted: bool = False,
    ) -> SimulatedNode:
        """A node playing ``profile``; ``serial_number`` replaces the profile's ``simulator.serial_number``;
        ``booted``: its first boot-up without the boot delay (it was switched on before)."""
        if serial_number is not None:
            profile = with_serial_number(profile, serial_number)
        node = SimulatedNode(profile, self.scheduler, self._send_from(None), node_id, nvm_path, faults)
        node._send_raw = self._send_from(node)
        self.nodes.append(node)
        if power_on:
            node.power_on(at_once=booted)
        return node

    def add_siblings(self, power_on: bool = True) -> list[SimulatedNode]:
        """Put the sibling of every node with a ``second_node`` quirk on the bus (unless its id is taken).

        The sibling plays ``params.profile`` (default: the same profile) at node-id + offset, with
        its own NVM file next to the node's and no faults: the faults belong to the device under test.
        """
        added = []
        for node in list(self.nodes):
            spec = sibling_spec(node)
            if spec is None or any(n.configured_node_id == spec[1] for n in self.nodes):
                continue
            profile, node_id = spec
            nvm = node.nvm.path
            nvm_path = None if nvm is None else nvm.with_name(f"{nvm.stem}-sibling{node_id}{nvm.suffix}")
            sibling = self.add_node(profile, node_id, nvm_path, FaultSet(), power_on)
            self._primary_of[id(sibling)] = node
            added.append(sibling)
        return added

    def device_nodes(self, node: SimulatedNode) -> list[SimulatedNode]:
        """``node`` and the siblings that share its device (and its power supply)."""
        return [node, *(n for n in self.nodes if self._primary_of.get(id(n)) is node)]

    def node(self, node_id: int | None = None) -> SimulatedNode:
        """The node with ``node_id`` (or the only node that is not a sibling)."""
        if node_id is None:
            primaries = [n for n in self.nodes if id(n) not in self._primary_of]
            if len(primaries) != 1:
                raise LookupError(f"{len(primaries)} nodes on the bus; name a node-id")
            return primaries[0]
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
            others = [other for other in self.nodes if other is not origin]
            if others:  # the other nodes on this bus hear it too, on the scheduler's thread (see _deliver)
                self.scheduler.call_at(time.monotonic(), lambda: self._deliver(msg, others))

        return send

    @staticmethod
    def _deliver(msg: can.Message, nodes: list[SimulatedNode]) -> None:
        """A frame one node sent, to the other nodes of this host. Not in the sender's thread: the sender holds
        its own node's lock (a scheduled boot-up, an answer), and handing the frame over there took the other
        node's lock too, while the receive thread, answering that other node, waited for the sender's: two
        nodes on one bus (WayCon MH) deadlocked after a broadcast reset, once in a CI run."""
        for node in nodes:
            try:
                node.on_frame(msg)
            except Exception:
                log.exception("node %s failed on frame %s", node.node_id, msg)

    def _dispatch(self, msg: can.Message) -> None:
        # the virtual bus stamps a frame when it is put on the bus: a frame handled much later (the twin's
        # process stalled on a loaded host) makes the answer late, which is the host's doing, not the device's
        late_ms = (time.time() - msg.timestamp) * 1000
        if late_ms > NOTED_RECEIVE_LAG_MS:
            self.scheduler.note_lateness(late_ms)
        for node in self.nodes:
            try:
                node.on_frame(msg)
            except Exception:
                log.exception("node %s failed on frame %s", node.node_id, msg)

    def serve_remote(self, host: str = "127.0.0.1", port: int = 0) -> tuple[str, int]:
        """Serve this bus to other processes (python-can-remote); returns the bound address."""
        from can_remote.server import RemoteServer

        logging.getLogger("can_remote").setLevel(logging.WARNING)
        self._dispatch_in_sender_thread()
        self._remote = RemoteServer(host, port, channel=self.channel, **server_config())
        self._remote.clients = _ClientsSentDirectly()  # frames to a tester sent in the sender's thread
        # a short poll: shutdown() waits for the serving loop to notice (the default 0.5 s is a run's end)
        server = self._remote
        threading.Thread(target=lambda: server.serve_forever(poll_interval=SERVER_POLL_S), name="remote-server",
                         daemon=True).start()
        return host, self._remote.server_port

    def _dispatch_in_sender_thread(self) -> None:
        """Frames from remote testers are handled in the server thread that received them, not handed to a
        receive thread of ours first: one thread switch less per frame (measured: SDO round trips per second +20 %).

        python-can's virtual bus delivers a frame by ``put`` on each listener's queue; our listener is an
        object whose ``put`` dispatches at once (one frame at a time, in arrival order). DESIGN: this leans
        on VirtualBus keeping its listeners as a list of queues (python-can 4.x); ``test_sim_host`` checks it.
        """
        if not isinstance(self.bus, VirtualBus):
            return
        self._notifier.stop()
        # cast: python-can types the list as holding Queues; the stand-in has the one method it calls, put
        direct = cast("Queue[can.Message]", _DirectDispatch(self._dispatch))
        channel = self.bus.channel  # the list of listener queues of this virtual channel
        with channels_lock:
            channel[channel.index(self.bus.queue)] = direct
        self.bus.queue = direct  # its own frames are still not delivered to it

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


def with_serial_number(profile: DeviceProfile, serial: int) -> DeviceProfile:
    """``profile`` as the unit with serial number ``serial``: 1018h sub 4 and 650Bh, and any
    ``simulator.values`` entry that repeats the profile's own serial number (a value the profile
    sets otherwise, e.g. FFFFFFFFh for "not reported", stays)."""
    sim = profile.simulator
    values = {key: serial if value == sim.serial_number and key.lower() in _SERIAL_KEYS else value
              for key, value in sim.values.items()}
    return profile.model_copy(update={"simulator": sim.model_copy(update={"serial_number": serial,
                                                                          "values": values})})


_SERIAL_KEYS = {"0x1018.4", "0x650b", "0x650b.0"}


def sibling_spec(node: SimulatedNode) -> tuple[DeviceProfile, int] | None:
    """(profile, node-id) of the sibling a ``second_node`` quirk asks for, or None."""
    params = node.profile.params_of(SecondNode)
    if params is None:
        return None
    node_id = node.configured_node_id + params.node_id_offset
    if not 1 <= node_id <= 127:
        log.warning("second_node: sibling node-id %d of node %d is outside 1..127", node_id, node.configured_node_id)
        return None
    name = params.profile
    profile = node.profile if not name or name == node.profile.id else load_profile(str(name)).profile
    return profile, node_id
