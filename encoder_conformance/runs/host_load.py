"""A busy process beside a run: the tester's PC under load, as on a bench PC that also runs other work."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import TracebackType

BUSY_LOOP = [sys.executable, "-c", "while True: pass"]


@contextmanager
def busy_process(enabled: bool = True) -> Iterator[None]:
    """Keep one core busy (a Python loop in its own process) while the block runs."""
    if not enabled:
        yield
        return
    process = subprocess.Popen(BUSY_LOOP)
    try:
        yield
    finally:
        process.kill()
        process.wait()


class BusyGate:
    """One busy process that spins only while someone holds it (``held()``), stopped (SIGSTOP) otherwise: the
    load sits on the moments a check measures, not on the minutes of preparation around them, whose length it
    only stretched. Thread-safe; holders overlap on the same process (never more than one core busy)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._holders = 0
        self._process: subprocess.Popen[bytes] | None = None

    def __enter__(self) -> BusyGate:
        self._process = subprocess.Popen(BUSY_LOOP)
        self._process.send_signal(signal.SIGSTOP)
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None:
        assert self._process is not None
        self._process.kill()
        self._process.wait()

    @contextmanager
    def held(self) -> Iterator[None]:
        """The process spins from now until the block ends (or the last other holder's does)."""
        self._hold(+1)
        try:
            yield
        finally:
            self._hold(-1)

    def _hold(self, step: int) -> None:
        assert self._process is not None, "BusyGate.held() outside its with-block"
        with self._lock:
            self._holders += step
            if self._holders == (1 if step > 0 else 0):
                self._process.send_signal(signal.SIGCONT if step > 0 else signal.SIGSTOP)
