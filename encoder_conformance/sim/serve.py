"""Run simulated nodes as a process: serve the bus (python-can-remote) and the control channel."""

from __future__ import annotations

import json
import logging
import os
import signal
import sys
import threading
import time
from pathlib import Path

from ..profile.loader import load_profile
from .control import parse_address, serve_control
from .faults import FaultSet
from .host import SimulatorHost


def serve(
    profiles: list[str],
    listen: str,
    control: str | None,
    node_ids: list[int],
    faults: list[str],
    nvm: Path | None,
    ready_line: bool,
) -> int:
    """Start the host, add one node per profile, print the endpoints, run until signalled."""
    # Timing: the default 5 ms GIL switch interval delays the scheduler thread by up to 5 ms when
    # the receive/remote threads are busy; 0.5 ms keeps heartbeat jitter well below the CI
    # tolerance (reference/python-stack-measured.md §6: p99 4.9 ms -> 1.8 ms).
    sys.setswitchinterval(0.0005)
    # python-can-remote reports a dropped client through logging only: into the simulator's log
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr, format="%(asctime)s %(name)s: %(message)s")
    host = SimulatorHost(channel=f"sim-{time.monotonic_ns()}")
    for i, name in enumerate(profiles):
        loaded = load_profile(name)
        node_id = node_ids[i] if i < len(node_ids) else None
        nvm_path = None if nvm is None else nvm.with_name(f"{nvm.stem}-{i}{nvm.suffix}") if i else nvm
        host.add_node(loaded.profile, node_id, nvm_path, FaultSet(faults))
    host.add_siblings()  # second_node quirk: the redundant interface's other node
    can_host, can_port = host.serve_remote(*parse_address(listen))
    control_address = serve_control(host, parse_address(control)) if control else None
    info = {
        "can": f"ws://{can_host}:{can_port}/",
        "control": control_address,
        "node_id": host.nodes[0].node_id,
        "nodes": [node.describe() for node in host.nodes],
    }
    if ready_line:
        print("READY " + json.dumps(info), flush=True)
    else:
        print(f"simulating {', '.join(profiles)} on {info['can']} (node-ids {[n.node_id for n in host.nodes]})")
        print(f"connect with: --can-interface remote --can-channel {info['can']}")
        if control_address:
            print(f"control channel on {control_address[0]}:{control_address[1]}")
        print("Ctrl-C stops the simulator.", flush=True)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        while not stop.wait(1.0):
            pass
    except KeyboardInterrupt:
        pass
    host.shutdown()  # the memory is written on every store, so nothing is left to save here
    sys.stdout.flush()
    sys.stderr.flush()
    # the web-socket server's threads make the interpreter's own shutdown take ~0.1 s, every run's end
    os._exit(0)
