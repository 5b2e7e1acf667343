"""Run simulated nodes as a process: serve the bus (python-can-remote, or sit on a CAN bus such as a vcan) and
the control channel.

``plan_nodes`` says which nodes the bus gets: one per profile, or N copies of one profile that differ
by serial number (base, base+1, ...) and have consecutive node-IDs, or wait unconfigured (node-ID 255)
for an LSS master to give them one.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import can

from encoder_conformance.cia.cia305 import MAX_NODE_ID, UNCONFIGURED_NODE_ID
from encoder_conformance.errors import SimulatorStop
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.quirk_effects import SecondNode
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.control import parse_address
from encoder_conformance.sim.engine.control_server import serve_control
from encoder_conformance.sim.engine.faults import FaultSet
from encoder_conformance.sim.engine.host import SimulatorHost
from encoder_conformance.sim.engine.host_priority import raise_twin_priority
from encoder_conformance.sim.engine.sim_log import configure_logging, log


@dataclass(frozen=True)
class NodePlan:
    """One node to put on the bus: its profile, node-ID (None: the profile's) and serial number (None: the
    profile's ``simulator.serial_number``)."""

    profile: DeviceProfile
    node_id: int | None
    serial_number: int | None = None


def plan_nodes(profiles: list[str], node_ids: list[int], copies: int = 1,
               unconfigured: bool = False) -> list[NodePlan]:
    """The nodes ``sim`` serves; ValueError says what is wrong with the combination (a usage error)."""
    loaded = [load_profile(name).profile for name in profiles]
    if unconfigured:
        if node_ids:
            raise ValueError("--unconfigured nodes have node-ID 255 until LSS gives them one: drop --node-id")
        for profile in loaded:
            missing = {"configure_node_id", "switch_selective"} - set(profile.capabilities.lss)
            if missing:
                raise ValueError(f"profile {profile.id} declares no LSS {' and '.join(sorted(missing))} "
                                 "(capabilities.lss): an unconfigured copy could never be given a node-ID")
    if copies == 1:
        return [NodePlan(p, UNCONFIGURED_NODE_ID if unconfigured else (node_ids[i] if i < len(node_ids) else None))
                for i, p in enumerate(loaded)]
    if len(loaded) != 1:
        raise ValueError("--copies serves copies of one profile: give --profile once")
    profile = loaded[0]
    if profile.params_of(SecondNode) is not None:
        raise ValueError(f"profile {profile.id} puts a second node on the bus (quirk second_node): copies of it "
                         "would take each other's node-IDs; serve one")
    if copies > MAX_NODE_ID:
        raise ValueError(f"--copies {copies}: a CANopen network has at most {MAX_NODE_ID} nodes")
    if len(node_ids) > 1:
        raise ValueError("--copies takes one --node-id: the first copy's (the others follow it)")
    serials = [profile.simulator.serial_number + n for n in range(copies)]
    if unconfigured:
        return [NodePlan(profile, UNCONFIGURED_NODE_ID, serial) for serial in serials]
    first = node_ids[0] if node_ids else profile.bus.node_id
    if first + copies - 1 > MAX_NODE_ID:
        raise ValueError(f"--copies {copies} from node-ID {first} needs node-IDs up to {first + copies - 1}, "
                         f"beyond {MAX_NODE_ID}: start lower (--node-id) or serve fewer copies")
    return [NodePlan(profile, first + n, serial) for n, serial in enumerate(serials)]


def serve(
    plan: list[NodePlan],
    listen: str,
    control: str | None,
    faults: list[str],
    nvm: Path | None,
    ready_line: bool,
    can_bus: tuple[str, str] | None = None,
) -> int:
    """Start the host, add the planned nodes, print the endpoints, run until signalled.

    ``can_bus`` (interface, channel): put the nodes on that CAN bus (e.g. socketcan on a vcan, the user-space
    one too) instead of serving a python-can-remote endpoint, as a firmware simulator would sit on it.

    ValueError: a port could not be taken, or the CAN bus not opened (the message names the option and the
    fix; a usage error)."""
    # Timing: the default 5 ms GIL switch interval delays the scheduler thread by up to 5 ms when
    # the receive/remote threads are busy; 0.5 ms keeps heartbeat jitter well below the CI
    # tolerance (reference/python-stack-measured.md §6: p99 4.9 ms -> 1.8 ms).
    sys.setswitchinterval(0.0005)
    configure_logging()
    priority = raise_twin_priority()  # before any thread starts: they inherit it
    host = _open_host(can_bus)
    try:  # the ports first: a port in use is one line, before any node has powered on
        if can_bus is None:
            can_host, can_port = _bind("--listen", listen, lambda address: host.serve_remote(*address))
            can_url = f"ws://{can_host}:{can_port}/"
        else:
            can_url = f"{can_bus[0]}:{can_bus[1]}"
        control_address = (_bind("--control", control, lambda address: serve_control(host, address))
                           if control else None)
    except ValueError:
        host.shutdown()
        raise
    _log_plan([(node.profile.id, node.node_id) for node in plan], faults, nvm)
    for i, node in enumerate(plan):
        nvm_path = None if nvm is None else nvm.with_name(f"{nvm.stem}-{i}{nvm.suffix}") if i else nvm
        # booted: a served twin is switched on before a tester connects, as a device on a bench is (a run
        # does not wait for a POSITAL's 4 s power-on boot before its first request)
        host.add_node(node.profile, node.node_id, nvm_path, FaultSet(faults), serial_number=node.serial_number,
                      booted=True)
    host.add_siblings()  # second_node quirk: the redundant interface's other node
    info = {
        "can": can_url,
        "control": control_address,
        "node_id": host.nodes[0].node_id,
        "nodes": [{**node.describe(), "serial_number": node.profile.simulator.serial_number}
                  for node in host.nodes],
    }
    log.info("%s", priority)  # once the ports are taken: a port in use stays a one-line error
    _log_start(host, can_url, control_address)
    if ready_line:
        print("READY " + json.dumps(info), flush=True)
    else:
        print(f"simulating {_describe(host)} on {info['can']}")
        connect = (f"--can-interface remote --can-channel {can_url}" if can_bus is None else
                   f"--can-interface {can_bus[0]} --can-channel {can_bus[1]}")
        print(f"connect with: {connect}")
        if control_address:
            print(f"control channel on {control_address[0]}:{control_address[1]}")
        print("Ctrl-C stops the simulator.", flush=True)
    stop = threading.Event()
    reason = "the tester gone"
    try:
        signal.signal(signal.SIGTERM, _terminated)
        if ready_line:  # started by a tester (sim/process.py): stop when it is gone (its end of our stdin closes)
            threading.Thread(target=_stop_at_end_of_input, args=(stop,), name="parent-watch", daemon=True).start()
        while not stop.wait(1.0):
            pass
    except KeyboardInterrupt:
        reason = "Ctrl-C"
    except SimulatorStop:
        reason = "SIGTERM"
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a second one ends the process at once
    log.info("stopping: %s", reason)
    host.shutdown()  # the memory is written on every store, so nothing is left to save here
    sys.stdout.flush()
    sys.stderr.flush()
    # the web-socket server's threads make the interpreter's own shutdown take ~0.1 s, every run's end
    os._exit(0)


def _open_host(can_bus: tuple[str, str] | None) -> SimulatorHost:
    """The host on a private virtual channel (served to testers through python-can-remote), or on a CAN bus."""
    if can_bus is None:
        return SimulatorHost(channel=f"sim-{time.monotonic_ns()}")
    interface, channel = can_bus
    try:
        return SimulatorHost(channel=channel, interface=interface)
    except (OSError, ValueError, ImportError, can.CanError) as exc:
        hint = (" (no vcan here? start the user-space bus: eval \"$(encoder-conformance vcan up)\")"
                if interface == "socketcan" else "")
        raise ValueError(f"--can-interface {interface} --can-channel {channel}: cannot open the bus: {exc}{hint}") \
            from None


def _terminated(*_: object) -> None:
    """SIGTERM: raised in the main thread out of its wait; the handler takes no lock (an ``Event.set()`` here
    deadlocked a twin whose main thread held that Event's lock inside ``stop.wait()``, seen in a fault matrix)."""
    raise SimulatorStop


def _stop_at_end_of_input(stop: threading.Event) -> None:
    """Block until stdin ends (the process that started us ended, also by SIGKILL), then ask serve to stop."""
    with contextlib.suppress(OSError, ValueError):
        while sys.stdin.buffer.read(4096):
            pass
    stop.set()


def _bind(option: str, text: str, serve_at: Callable[[tuple[str, int]], tuple[str, int]]) -> tuple[str, int]:
    """``serve_at(address)``; a port in use or an address that cannot be had becomes a ValueError naming
    ``option`` and the fix."""
    try:
        address = parse_address(text)
    except ValueError:
        raise ValueError(f"{option} {text}: not HOST:PORT; give e.g. 127.0.0.1:54701 (port 0 picks a free one)") \
            from None
    try:
        return serve_at(address)
    except OSError as exc:
        if exc.errno == errno.EADDRINUSE:
            raise ValueError(f"{option} {text}: port {address[1]} is in use; choose another port (0 picks a free "
                             f"one) or stop the program holding it") from None
        raise ValueError(f"{option} {text}: cannot listen there ({exc.strerror or exc}); give an address of this "
                         "machine, e.g. 127.0.0.1:PORT") from None


def _log_plan(profiles: list[tuple[str, int | None]], faults: list[str], nvm: Path | None) -> None:
    """What this simulator is about to play: before the nodes power on, so the log reads in order."""
    nodes = ", ".join(f"{profile_id} (node-ID {node_id or 'from the profile'})" for profile_id, node_id in profiles)
    log.info("starting: %s; faults: %s; NVM %s", nodes, ", ".join(faults) or "none", nvm or "in memory")


def _log_start(host: SimulatorHost, can_url: str, control: tuple[str, int] | None) -> None:
    """Where this simulator listens, and each node as it came up."""
    log.info("serving the bus on %s; control channel %s", can_url,
             f"{control[0]}:{control[1]}" if control else "none")
    for node in host.nodes:
        log.info("node %d: profile %s (%s), serial number %d, faults: %s", node.node_id, node.profile.id,
                 node.profile.title, node.profile.simulator.serial_number, ", ".join(sorted(node.faults.names)) or
                 "none")


def _describe(host: SimulatorHost) -> str:
    """'cia406-c3-st x8 (serials 40600001..40600008, node-ids [255, ...])'."""
    names = [node.profile.id for node in host.nodes]
    serials = [node.profile.simulator.serial_number for node in host.nodes]
    node_ids = [node.node_id for node in host.nodes]
    if len(set(names)) == 1 and len(names) > 1:
        return f"{names[0]} x{len(names)} (serials {serials[0]}..{serials[-1]}, node-ids {node_ids})"
    return f"{', '.join(names)} (node-ids {node_ids})"
