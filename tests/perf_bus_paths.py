"""SDO round trips per second and heartbeat jitter against the twin over the two buses a run can use
between processes: python-can-remote (the built-in simulator's default) and the user-space SocketCAN bus
(``encoder-conformance vcan``, where a firmware simulator sits). Not collected by pytest; run
``python tests/perf_bus_paths.py [SECONDS]``. Issue 28 asks for the figures side by side.
"""

from __future__ import annotations

import itertools
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import canopen

from encoder_conformance.sim.process import start_simulator

PROFILE = "wachendorff-wdga-mt"
HEARTBEAT_MS = 10
HEARTBEATS = 300


def measure(bus_kwargs: dict[str, object], node_id: int, seconds: float) -> dict[str, float]:
    """SDO uploads of 1000h per second, then the heartbeat intervals at 1017h = HEARTBEAT_MS (put back to 0)."""
    network = canopen.Network()
    network.connect(**bus_kwargs)
    try:
        node = network.add_node(canopen.RemoteNode(node_id, canopen.ObjectDictionary()))
        node.sdo.MAX_RETRIES = 30  # the twin may still be booting: its first answer is waited for
        node.sdo.upload(0x1000, 0)
        node.sdo.MAX_RETRIES = 1
        for _ in range(50):
            node.sdo.upload(0x1000, 0)
        done, start = 0, time.perf_counter()
        while time.perf_counter() - start < seconds:
            node.sdo.upload(0x1000, 0)
            done += 1
        rate = done / (time.perf_counter() - start)
        stamps: list[float] = []
        enough = threading.Event()

        def heartbeat(can_id: int, data: bytearray, timestamp: float) -> None:
            stamps.append(timestamp)
            if len(stamps) > HEARTBEATS:
                enough.set()

        network.subscribe(0x700 + node_id, heartbeat)
        node.sdo.download(0x1017, 0, HEARTBEAT_MS.to_bytes(2, "little"))
        enough.wait(HEARTBEATS * HEARTBEAT_MS / 1000 * 3)
        node.sdo.download(0x1017, 0, b"\x00\x00")
    finally:
        network.disconnect()
    intervals = [(b - a) * 1000 for a, b in itertools.pairwise(stamps)]
    deviation = sorted(abs(i - HEARTBEAT_MS) for i in intervals)
    return {"sdo_per_s": round(rate), "heartbeats": len(intervals),
            "interval_median_ms": round(statistics.median(intervals), 3),
            "deviation_p99_ms": round(deviation[int(0.99 * (len(deviation) - 1))], 3),
            "deviation_max_ms": round(deviation[-1], 3)}


def over_remote(seconds: float) -> dict[str, float]:
    sim = start_simulator(PROFILE)
    try:
        return measure(sim.bus_kwargs, sim.node_id, seconds)
    finally:
        sim.stop()


def over_user_space_socketcan(seconds: float) -> dict[str, float]:
    tool = [sys.executable, "-m", "encoder_conformance"]
    with tempfile.TemporaryDirectory() as hub:
        exports = subprocess.run([*tool, "vcan", "up", "-d", hub, "--mode", "wire", "vcan0"], check=True,
                                 capture_output=True, text=True).stdout
        env = {**os.environ, **dict(re.findall(r"export (\w+)=['\"]?([^'\"\n]*)", exports))}
        sim = subprocess.Popen([*tool, "sim", "--profile", PROFILE, "--can-interface", "socketcan", "--can-channel",
                                "vcan0", "--ready-line"], env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                               stdin=subprocess.PIPE, text=True)  # stdin held open: the twin stops at its end of file
        try:
            assert sim.stdout is not None
            ready = next(line for line in sim.stdout if line.startswith("READY "))
            node_id = json.loads(ready.split(" ", 1)[1])["node_id"]
            done = subprocess.run([sys.executable, __file__, "--measure", str(seconds), str(node_id)], env=env,
                                  check=False, capture_output=True, text=True)
            if done.returncode:
                raise RuntimeError(done.stderr[-2000:])
            return json.loads(done.stdout.strip().splitlines()[-1])
        finally:
            sim.terminate()
            sim.wait(10)
            subprocess.run([*tool, "vcan", "down", "-d", hub], check=False, capture_output=True)


def main() -> None:
    if sys.argv[1:2] == ["--measure"]:  # the measuring side, run under the preload library
        print(json.dumps(measure({"interface": "socketcan", "channel": "vcan0"}, int(sys.argv[3]),
                                 float(sys.argv[2]))))
        return
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 3.0
    for name, path in (("python-can-remote", over_remote), ("user-space SocketCAN", over_user_space_socketcan)):
        print(f"{name:22s} {path(seconds)}", flush=True)


if __name__ == "__main__":
    main()
