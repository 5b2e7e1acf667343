"""A busy process beside a run: the tester's PC under load, as on a bench PC that also runs other work."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def busy_process(enabled: bool = True) -> Iterator[None]:
    """Keep one core busy (a Python loop in its own process) while the block runs."""
    if not enabled:
        yield
        return
    process = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        yield
    finally:
        process.kill()
        process.wait()
