"""Run pytest sessions (a suite against a twin) in children forked from a pre-loaded server.

The fault matrix and the self-tests run the suites a few hundred times, each as its own pytest session,
as a user runs them. As separate interpreters (``subprocess``), each spent ~1.5 s importing pytest,
python-can, canopen, pydantic and this library before its first test (measured on one targeted fault run,
median of 3: 3.7 s as a subprocess, 2.3 s forked). multiprocessing's forkserver start method (stdlib)
imports them once in a single-threaded server and forks a fresh child per session: each child is a new
process with its own pytest session, its own simulator and nothing shared with the caller (or with the
other children) but the imported modules.

The libraries of the pytest plugins found through entry points (hypothesis, pytest-html, pytest-metadata) are
preloaded too: each child spent ~80 ms importing them (measured: a forked session of one suite module, median of
4, 0.42 s -> 0.34 s). pytest marks a plugin's modules for assertion rewriting and warns (PytestAssertRewriteWarning)
where one is imported already; for the preloaded ones that is the server's doing, not the session's, so a session
filters exactly those warnings (``option_table.imported_before_pytest``). A session loads no plugin a run does not use
(``option_table.unused_plugins``: anyio's, allure-pytest's unless asked for), as ``encoder-conformance run``.
"""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from encoder_conformance.plugin.option_table import imported_before_pytest, unused_plugins
from encoder_conformance.runs.session_slots import SESSION_SLOTS
from encoder_conformance.sim.twin import SERVE_MODULE

#: the libraries of the pytest plugins a session loads through entry points (not the plugin modules themselves)
ENTRY_POINT_LIBRARIES = ("hypothesis", "pytest_html", "pytest_metadata")
#: the modules of the plugins' distributions the server imports (hypothesis imports its _hypothesis_globals)
PRELOADED_DISTRIBUTION_MODULES = ("encoder_conformance", *ENTRY_POINT_LIBRARIES, "_hypothesis_globals")
#: imported once in the fork server (the heavy imports of a session)
PRELOAD = ["pytest", "_pytest.assertion.rewrite", "_pytest.python", "jinja2", "allure_commons", "attr", "can",
           "canopen", "pydantic", "yaml", "encoder_conformance.profile.loader", "encoder_conformance.dut.device",
           "encoder_conformance.sim.process", "encoder_conformance.plugin.hooks",
           SERVE_MODULE, *ENTRY_POINT_LIBRARIES]
#: how long a child may take to stop after SIGTERM before it is killed
STOP_GRACE_S = 5.0

_context: multiprocessing.context.ForkServerContext | None = None


@dataclass(frozen=True)
class SessionResult:
    """What a pytest session ended with: its exit code and its terminal output (stdout and stderr)."""

    returncode: int
    output: str


def _forkserver() -> multiprocessing.context.ForkServerContext:
    global _context
    if _context is None:
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(PRELOAD)
        _context = context
    return _context


def _session(args: list[str], cwd: str, env: dict[str, str], output: str) -> None:
    """In the child: the environment and folder asked for, both output streams into ``output``, one session."""
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(env)
    descriptor = os.open(output, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    os.dup2(descriptor, 1)
    os.dup2(descriptor, 2)
    import pytest

    sys.argv = ["pytest", *args]
    try:
        code = int(pytest.main(args))
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
    os._exit(code)


def run_pytest(args: Sequence[str], cwd: Path, output: Path, timeout: float,
               env: Mapping[str, str] | None = None) -> SessionResult:
    """One pytest session with ``args`` in ``cwd``; its output is kept in ``output``. Raises
    subprocess.TimeoutExpired (the child killed) after ``timeout`` seconds, as subprocess.run does. The session
    runs in one of the process's session slots (runs/session_slots.py); ``timeout`` counts from its start."""
    output.parent.mkdir(parents=True, exist_ok=True)
    argv = [*unused_plugins(list(args)), *imported_before_pytest(PRELOADED_DISTRIBUTION_MODULES), *args]
    child = _forkserver().Process(target=_session, name="pytest-session",
                                  args=(argv, str(cwd), dict(os.environ if env is None else env), str(output)))
    with SESSION_SLOTS.held():
        child.start()
        child.join(timeout)
        if child.exitcode is None:
            child.terminate()
            child.join(STOP_GRACE_S)
            if child.exitcode is None:
                child.kill()
                child.join()
            raise subprocess.TimeoutExpired(["pytest", *args], timeout, _read(output))
    return SessionResult(child.exitcode, _read(output))


def _read(path: Path) -> str:
    return path.read_text(encoding="utf-8", errors="replace") if path.exists() else ""
