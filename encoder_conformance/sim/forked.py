"""Start the simulator as a fork of this process instead of a new interpreter (Linux, single-threaded only).

A new interpreter spends ~0.3 s importing python-can, canopen, pydantic and the profile code before its READY
line (measured: 0.33 s, three launches of the WDGA twin); a run's first test waits for it. A pytest session
has imported most of that already, so a fork of it is serving in a fraction of that. The child is the same
``encoder-conformance sim`` command (its own session, stdin, stdout and log file, every other descriptor
closed), started through multiprocessing's ``fork`` context, whose Process handle waits and signals it.
The caller passes what the child runs (the simulator's ``serve``): this module imports nothing of it.

Not used where forking is unsafe: another thread could hold a lock the child would inherit (only a process
with one thread forks), and platforms whose system libraries break after fork (macOS) or that have none.
"""

from __future__ import annotations

import contextlib
import faulthandler
import gc
import logging
import multiprocessing
import os
import select
import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from typing import IO

__all__ = ["ForkedProcess", "can_fork", "fork_simulator"]


def can_fork() -> bool:
    """Forking is safe here: Linux, and no thread besides this one."""
    return sys.platform.startswith("linux") and threading.active_count() == 1


class ForkedProcess:
    """The forked simulator, with the part of ``subprocess.Popen`` the launcher uses."""

    def __init__(self, process: multiprocessing.process.BaseProcess, stdin_fd: int, stdout_fd: int) -> None:
        self._process = process
        self._stdin_fd = stdin_fd  # ours: when it closes (we end, however), the simulator reads end-of-file
        self.stdout: IO[str] | None = os.fdopen(stdout_fd, "r", encoding="utf-8")

    @property
    def pid(self) -> int | None:
        return self._process.pid

    @property
    def returncode(self) -> int | None:
        return self._process.exitcode

    def poll(self) -> int | None:
        return self._process.exitcode

    def wait(self, timeout: float | None = None) -> int:
        """The exit code; ``timeout``: TimeoutExpired if the child lives on. Waited on the process itself (a pidfd):
        the child closed multiprocessing's sentinel pipe with every inherited descriptor, so join(timeout) saw its
        end at once and then blocked in waitpid, and a twin that did not end hung its session (seen: 600 s)."""
        pid = self._process.pid
        if timeout is not None and self._process.exitcode is None and pid is not None:
            pidfd = os.pidfd_open(pid)
            try:
                ended, _, _ = select.select([pidfd], [], [], timeout)
            finally:
                os.close(pidfd)
            if not ended:
                raise subprocess.TimeoutExpired("simulator", timeout)
        self._process.join()
        code = self._process.exitcode
        assert code is not None  # joined
        return code

    def terminate(self) -> None:
        self._process.terminate()

    def kill(self) -> None:
        self._process.kill()


def fork_simulator(run: Callable[[], int], log_path: str | None) -> ForkedProcess:
    """``run()`` (which serves the simulator and prints its READY line) in a fork of this process, its exit code
    the child's (call only where ``can_fork()``)."""
    stdin_read, stdin_write = os.pipe()
    stdout_read, stdout_write = os.pipe()
    context = multiprocessing.get_context("fork")
    child = context.Process(target=_serve, args=(run, stdin_read, stdout_write, log_path), name="simulator",
                            daemon=True)  # daemonic: multiprocessing stops it if this process exits normally
    child.start()
    os.close(stdin_read)
    os.close(stdout_write)
    return ForkedProcess(child, stdin_write, stdout_read)


def _serve(run: Callable[[], int], stdin_fd: int, stdout_fd: int, log_path: str | None) -> None:
    """In the child: a session of its own, the three standard streams, nothing else inherited; then ``run``."""
    faulthandler.disable()  # pytest's writes to a descriptor of the parent's
    gc.freeze()  # the parent's heap (a whole pytest session) is never garbage: collections skip it
    gc.enable()  # the run forks it while its collector pauses for the collection (plugin/hooks.py)
    os.setsid()  # the terminal's Ctrl-C reaches only the run, which gives the device back first
    for number in (signal.SIGTERM, signal.SIGHUP, signal.SIGPIPE, signal.SIGCHLD):
        signal.signal(number, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    log = os.open(log_path or os.devnull, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    for source, target in ((stdin_fd, 0), (stdout_fd, 1), (log, 2)):
        os.dup2(source, target)
    _close_inherited_descriptors()
    sys.stdin = open(0, encoding="utf-8", closefd=False)  # noqa: SIM115
    sys.stdout = open(1, "w", encoding="utf-8", buffering=1, closefd=False)  # noqa: SIM115
    sys.stderr = open(2, "w", encoding="utf-8", buffering=1, closefd=False)  # noqa: SIM115
    logging.root.handlers.clear()  # the parent's (pytest's capture handlers) would swallow the simulator's log
    code = 1
    try:
        code = run()
    except BaseException:  # the log is the only place a failed start can be read
        import traceback

        traceback.print_exc()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def _close_inherited_descriptors() -> None:
    """Every descriptor but 0, 1 and 2: the parent's sockets, pipes and files are not the simulator's."""
    for name in os.listdir("/proc/self/fd"):
        if int(name) > 2:
            with contextlib.suppress(OSError):  # the listing's own descriptor, already closed
                os.close(int(name))
