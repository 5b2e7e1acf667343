"""Start a simulator in its own process and talk to it: the launcher and the control client.

The default for conformance runs. Imports nothing of the simulator but its control protocol.

The child prints one line ``READY {json}`` with the python-can-remote URL and the control
address once its bus is served; we wait for that line (with a timeout), not for a fixed time.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from multiprocessing.connection import Client, Connection
from pathlib import Path
from typing import IO, Any, Protocol

from encoder_conformance.sim import forked
from encoder_conformance.sim.control import AUTHKEY, ControlApi, parse_address

__all__ = ["LaunchedSimulator", "SimulatorControl", "SimulatorProcess", "launch_simulator", "parse_address",
           "start_simulator"]

READY_TIMEOUT_S = 30.0
STOP_TIMEOUT_S = 1.0


class ProcessHandle(Protocol):
    """What the launcher needs of the simulator's process: ``subprocess.Popen``, or a forked one (sim/forked.py)."""

    stdout: IO[str] | None

    @property
    def pid(self) -> int | None: ...

    @property
    def returncode(self) -> int | None: ...

    def poll(self) -> int | None: ...

    def wait(self, timeout: float | None = None) -> int: ...

    def terminate(self) -> None: ...

    def kill(self) -> None: ...


@dataclass
class SimulatorProcess:
    process: ProcessHandle
    can_url: str
    control: tuple[str, int]
    node_id: int
    log_path: Path | None

    @property
    def bus_kwargs(self) -> dict[str, object]:
        return {"interface": "remote", "channel": self.can_url, "receive_own_messages": False}

    def stop(self) -> None:
        """SIGTERM, then SIGKILL after STOP_TIMEOUT_S: a run's end never waits long for its twin."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()


def start_simulator(
    profile: str,
    node_id: int | None = None,
    faults: list[str] | None = None,
    nvm_path: Path | None = None,
    log_path: Path | None = None,
    extra_args: Sequence[str] = (),
) -> SimulatorProcess:
    """Launch ``encoder-conformance sim`` and wait until it reports READY."""
    return launch_simulator(profile, node_id, faults, nvm_path, log_path, extra_args).ready()


@dataclass
class LaunchedSimulator:
    """A simulator process that is starting: ``ready()`` waits for its READY line (a run launches it
    before collecting the tests, so that its start-up overlaps the collection)."""

    process: ProcessHandle
    command: list[str]
    log_path: Path | None
    _lines: list[str]
    _reader: threading.Thread

    def ready(self) -> SimulatorProcess:
        self._reader.join(READY_TIMEOUT_S)
        if not self._lines:
            self.process.kill()
            log = self.log_path
            detail = log.read_text(encoding="utf-8")[-2000:] if log and log.exists() else ""
            raise RuntimeError(f"simulator did not start within {READY_TIMEOUT_S:.0f} s: {' '.join(self.command)}\n"
                               f"{detail}")
        info = json.loads(self._lines[0].split(" ", 1)[1])
        return SimulatorProcess(self.process, info["can"], tuple(info["control"]), info["node_id"], self.log_path)

    def abandon(self) -> None:
        """Stop it (it was launched but the run did not need it)."""
        SimulatorProcess(self.process, "", ("", 0), 0, self.log_path).stop()


def launch_simulator(
    profile: str,
    node_id: int | None = None,
    faults: list[str] | None = None,
    nvm_path: Path | None = None,
    log_path: Path | None = None,
    extra_args: Sequence[str] = (),
    fork: bool = False,
) -> LaunchedSimulator:
    """Start ``encoder-conformance sim`` in a process of its own; returns at once. ``extra_args`` go to ``sim``
    (e.g. ``--copies 8 --unconfigured``). ``fork``: as a fork of this process where that is safe (a run's own
    twin: serving in a fraction of a new interpreter's start-up, sim/forked.py), else a new interpreter."""
    args = ["--profile", profile, "--listen", "127.0.0.1:0", "--control", "127.0.0.1:0", "--ready-line"]
    if node_id is not None:
        args += ["--node-id", str(node_id)]
    for fault in faults or []:
        args += ["--fault", fault]
    if nvm_path is not None:
        args += ["--nvm", str(nvm_path)]
    args += list(extra_args)
    command = [sys.executable, "-m", "encoder_conformance", "sim", *args]
    process: ProcessHandle
    if fork and not extra_args and forked.can_fork():
        def serve_one() -> int:  # what ``sim`` with ``args`` does, less its usage checks (our own arguments)
            from encoder_conformance.sim.twin import plan_nodes, serve

            plan = plan_nodes([profile], [] if node_id is None else [node_id])
            return serve(plan, "127.0.0.1:0", "127.0.0.1:0", list(faults or []), nvm_path, True)

        process = forked.fork_simulator(serve_one, str(log_path) if log_path else None)
    else:
        stderr = open(log_path, "w", encoding="utf-8") if log_path else subprocess.DEVNULL  # noqa: SIM115
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        # a session of its own: the terminal's Ctrl-C reaches only the run, which gives the device back first
        # stdin a pipe that only this process holds: when it ends, however (even SIGKILL), the simulator reads
        # end-of-file and stops, instead of living on as an orphan holding its ports
        process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr,
                                   text=True, env=env, start_new_session=True)
    lines: list[str] = []

    def read_ready_line() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            if line.startswith("READY "):
                lines.append(line.strip())
                return

    reader = threading.Thread(target=read_ready_line, daemon=True)
    reader.start()
    return LaunchedSimulator(process, command, log_path, lines, reader)


class SimulatorControl(ControlApi):
    """Client: what the test side may ask of a simulated device."""

    def __init__(self, address: tuple[str, int], node_id: int | None = None) -> None:
        self._address = address
        self._node_id = node_id
        self._lock = threading.Lock()
        self._conn: Connection = Client(address, authkey=AUTHKEY)

    def _call(self, command: str, *args: Any) -> Any:
        with self._lock:
            self._conn.send((command, self._node_id, args))
            ok, result = self._conn.recv()
        if not ok:
            raise RuntimeError(f"simulator refused {command}{args}: {result}")
        return result

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self._conn.close()
