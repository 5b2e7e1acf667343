"""An external twin as a bench engineer meets a device: a separate simulator process with a customer
configuration stored in its memory, reached only over the bus (python-can-remote) and its power
switch (``encoder-conformance sim-control``, used as the run's --power-off-cmd/--power-on-cmd).

``read_everything`` reads every readable entry the profile declares (except those that change by
themselves) through a tester connection of its own, to compare the device before and after a run.
"""

from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import canopen
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from encoder_conformance.cia.cia301 import SAVE
from encoder_conformance.dut.link import connection
from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.sim.process import SimulatorControl, SimulatorProcess, start_simulator

REPO = Path(__file__).resolve().parents[1]
PROFILE = "wachendorff-wdga-mt"
#: the customer's configuration, written and stored with 1010h sub 1 before the device reaches the bench
CUSTOMER_VALUES = {(0x1017, 0): 1000, (0x1029, 1): 1, (0x1800, 5): 100, (0x6200, 0): 20, (0x6000, 0): 5}


@dataclass
class ExternalTwin:
    sim: SimulatorProcess
    nvm: Path
    profile: str
    runs: list[subprocess.Popen[str]] = field(default_factory=list)

    @property
    def channel(self) -> str:
        return self.sim.can_url

    def power_command(self, action: str) -> str:
        host, port = self.sim.control
        return shlex.join([sys.executable, "-m", "encoder_conformance", "sim-control", "--control",
                           f"{host}:{port}", action])

    def run_args(self, report_dir: Path, *extra: str) -> list[str]:
        """The bench engineer's command line against this device."""
        return [sys.executable, "-m", "encoder_conformance", "run", "--profile", self.profile,
                "--can-interface", "remote", "--can-channel", self.channel, "--report-dir", str(report_dir),
                "--allow-destructive", "--power-off-cmd", self.power_command("power-off"),
                "--power-on-cmd", self.power_command("power-on"), "--power-off-time", "0", *extra]

    def start_run(self, report_dir: Path, *extra: str) -> subprocess.Popen[str]:
        env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
        process = subprocess.Popen(self.run_args(report_dir, *extra), cwd=REPO, env=env, text=True,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        self.runs.append(process)
        return process

    def stored(self) -> dict[str, int | str]:
        """The twin's non-volatile memory as a file (what survives a power loss)."""
        return json.loads(self.nvm.read_text(encoding="utf-8"))["values"] if self.nvm.exists() else {}

    def power_cycle(self) -> None:
        control = SimulatorControl(self.sim.control)
        try:
            control.power_cycle()
        finally:
            control.close()

    def configure(self, values: dict[tuple[int, int], int]) -> None:
        """What the customer did: write the values, store them with 1010h sub 1 'save', power cycle."""
        profile = load_profile(self.profile).profile
        with self._client() as node:
            for (index, sub), value in values.items():
                size = datatypes.size_bytes(profile.entry(index, sub).type)
                node.sdo.download(index, sub, value.to_bytes(size, "little", signed=value < 0))
            node.sdo.download(0x1010, 1, SAVE)
        self.power_cycle()

    @contextmanager
    def _client(self) -> Iterator[canopen.RemoteNode]:
        frames = FrameLog()
        network = connection.connect({"interface": "remote", "channel": self.channel}, self.channel, frames)
        try:
            node = canopen.RemoteNode(self.sim.node_id, canopen.ObjectDictionary())
            network.add_node(node)
            node.sdo.RESPONSE_TIMEOUT = 1.0
            self._awake(network, node)
            yield node
        finally:
            connection.disconnect(network)

    def read_everything(self) -> dict[str, str]:
        """Every readable, non-dynamic declared entry as hex ('abort XXXXXXXX' where refused)."""
        profile = load_profile(self.profile).profile
        with self._client() as node:
            values = {}
            for index, sub, _, entry in profile.iter_entries():
                if not entry.readable or entry.dynamic:
                    continue
                try:
                    values[f"{index:04X}.{sub:02X}"] = node.sdo.upload(index, sub).hex()
                except SdoAbortedError as exc:
                    values[f"{index:04X}.{sub:02X}"] = f"abort {exc.code:08X}"
            return values

    def _awake(self, network: canopen.Network, node: canopen.RemoteNode) -> None:
        """A twin powered on a moment ago may wait for bus traffic (bit-rate detection): send a SYNC, then
        ask until it answers SDO (bounded)."""
        network.send_message(0x80, b"")
        deadline = time.monotonic() + 5.0
        node.sdo.RESPONSE_TIMEOUT = 0.1
        try:
            while True:
                try:
                    node.sdo.upload(0x1000, 0)
                    return
                except SdoCommunicationError:
                    if time.monotonic() > deadline:
                        raise
        finally:
            node.sdo.RESPONSE_TIMEOUT = 1.0

    def freeze(self) -> None:
        os.kill(self.sim.process.pid, signal.SIGSTOP)

    def kill(self) -> None:
        self.sim.process.kill()
        self.sim.process.wait(5)

    def close(self) -> None:
        for run in self.runs:
            if run.poll() is None:
                run.kill()
                run.communicate(timeout=10)
        if self.sim.process.poll() is None:
            os.kill(self.sim.process.pid, signal.SIGCONT)
        self.sim.stop()


def start_twin(folder: Path, customer: dict[tuple[int, int], int] | None = None,
               profile: str = PROFILE, variants: list[str] | None = None) -> ExternalTwin:
    """A twin in its own process (playing ``variants``: conformant readings the default twin does not play);
    ``customer`` values written and stored the customer's way (1010h)."""
    folder.mkdir(parents=True, exist_ok=True)
    sim = start_simulator(profile, faults=variants, nvm_path=folder / "nvm.json", log_path=folder / "twin.log")
    twin = ExternalTwin(sim, folder / "nvm.json", profile)
    if customer:
        twin.configure(customer)
    return twin


def _stored_value(twin: ExternalTwin, stored: dict, key: str) -> object:
    """What the memory holds for ``key`` ('0xIIII.S'): the file's value, else the factory default the twin's
    memory starts from (a real EEPROM always holds a value: 'never written' and 'written with the default'
    are the same device)."""
    if key in stored:
        return stored[key]
    index, sub = key.removeprefix("0x").split(".")
    entry = load_profile(twin.profile).profile.entry(int(index, 16), int(sub))
    return None if entry is None else entry.default


def as_found_problems(twin: ExternalTwin, before: dict[str, str], stored_before: dict) -> list[str]:
    """Every difference to the device as found: values, the memory, values after a power cycle."""
    problems = [f"{k}: {before[k]} -> {v}" for k, v in twin.read_everything().items() if before.get(k) != v]
    stored = twin.stored()
    problems += [f"stored {k}: {_stored_value(twin, stored_before, k)} -> {_stored_value(twin, stored, k)}"
                 for k in set(stored) | set(stored_before)
                 if _stored_value(twin, stored, k) != _stored_value(twin, stored_before, k)]
    twin.power_cycle()
    problems += [f"after power cycle {k}: {before[k]} -> {v}"
                 for k, v in twin.read_everything().items() if before.get(k) != v]
    return problems


def wait_for_line(process: subprocess.Popen[str], text: str, timeout: float, seen: list[str]) -> bool:
    """Read the run's output until a line holds ``text`` (lines are kept in ``seen``)."""
    assert process.stdout is not None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line:
            return False
        seen.append(line)
        if text in line:
            return True
    return False

