"""A simulator started by a tester never outlives it: killed with SIGKILL (no clean-up of its own), the
tester's end of the simulator's stdin closes and the simulator stops, freeing its ports; a forked simulator that
does not end on SIGTERM is waited for only as long as asked (then killed), not for ever."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
TESTER = """
import sys, time
from encoder_conformance.sim.process import launch_simulator
sim = launch_simulator("waycon-sx", fork=sys.argv[1] == "fork").ready()
print("SIMPID", sim.process.pid, flush=True)
time.sleep(120)
"""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@pytest.mark.parametrize("start", ["new interpreter", "fork"])
def test_simulator_stops_when_its_tester_is_killed(start: str):
    """Both ways a simulator is started (sim/process.py): a new interpreter, or a fork of the tester."""
    tester = subprocess.Popen([sys.executable, "-c", TESTER, start.split()[-1]], cwd=REPO, stdout=subprocess.PIPE,
                              text=True)
    try:
        assert tester.stdout is not None
        line = tester.stdout.readline()
        assert line.startswith("SIMPID "), line
        simulator = int(line.split()[1])
        assert _alive(simulator)
        tester.send_signal(signal.SIGKILL)
        tester.wait(10)
        deadline = time.monotonic() + 15
        while _alive(simulator) and time.monotonic() < deadline:
            time.sleep(0.05)  # polling a process that is not our child: no event to wait on
        still = _alive(simulator)
        if still:
            os.kill(simulator, signal.SIGKILL)
        assert not still, "the simulator lived on after its tester was killed (an orphan holding its ports)"
    finally:
        if tester.poll() is None:
            tester.kill()


STUBBORN = """
import signal, subprocess, time
from encoder_conformance.sim.forked import fork_simulator

def run():
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a simulator stuck in its stop (seen: a lock in a handler)
    print("READY", flush=True)
    time.sleep(60)
    return 0

child = fork_simulator(run, None)
child.stdout.readline()
child.terminate()
start = time.monotonic()
try:
    child.wait(timeout=0.3)
    print("ENDED")
except subprocess.TimeoutExpired:
    print("TIMEOUT", round(time.monotonic() - start, 2))
child.kill()
print("CODE", child.wait())
"""


def test_a_forked_simulator_that_does_not_end_is_waited_for_only_as_asked():
    """ForkedProcess.wait(timeout) returns at the timeout: the child closed multiprocessing's sentinel pipe with
    every inherited descriptor, and a join(timeout) then blocked in waitpid until the session's own timeout."""
    completed = subprocess.run([sys.executable, "-c", STUBBORN], cwd=REPO, capture_output=True, text=True,
                               timeout=30)
    lines = completed.stdout.split("\n")
    assert lines[0].startswith("TIMEOUT "), completed.stdout + completed.stderr
    assert float(lines[0].split()[1]) < 5.0
    assert lines[1] == f"CODE {-signal.SIGKILL}", completed.stdout
