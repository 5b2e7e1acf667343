"""A twin asks the host for a higher scheduling weight (sim/engine/host_priority.py): a device has a processor of
its own, and a loaded host must not make a conformant twin's timers late."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from encoder_conformance.sim.engine.host_priority import TWIN_NICE, raise_twin_priority
from encoder_conformance.sim.process import launch_simulator


def _nice_of(pid: int) -> int:
    """The nice value of a process's main thread (/proc/PID/stat field 19)."""
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[16])


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the nice value from Linux /proc")
def test_a_served_twin_runs_at_the_twin_weight_where_the_host_allows_it(tmp_path):
    log = tmp_path / "sim.log"
    sim = launch_simulator("waycon-sx", log_path=log).ready()
    try:
        assert sim.process.pid is not None
        nice = _nice_of(sim.process.pid)
    finally:
        sim.stop()
    line = next(line for line in log.read_text(encoding="utf-8").splitlines() if "scheduling priority" in line)
    if os.geteuid() == 0:  # root may lower its nice value: the twin must have done so
        assert nice == TWIN_NICE, line
        assert f"-> {TWIN_NICE}" in line
    else:  # an ordinary user may not: the twin keeps the weight it had and says so
        assert nice == os.getpriority(os.PRIO_PROCESS, 0), line
        assert "kept" in line


def test_a_twin_not_permitted_keeps_its_weight_and_says_so(monkeypatch):
    """Where the kernel refuses (an ordinary user: EPERM), the twin keeps its weight, and its log line says why."""
    def refuse(which: int, who: int, value: int) -> None:
        raise PermissionError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(os, "getpriority", lambda which, who: 0)
    monkeypatch.setattr(os, "setpriority", refuse)
    line = raise_twin_priority()
    assert "nice 0 kept (Operation not permitted" in line
    assert f"-> {TWIN_NICE}" not in line
