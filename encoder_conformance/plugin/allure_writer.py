"""Allure result files written on a background thread.

allure-pytest serialises and writes one JSON file per test and per fixture set-up (about 2,900
files for a WDGA run), on the test thread: measured 3.0 s of a 14.4 s run. The files are written
as they were, only later: each result object is handed over once allure is done with it, and the
queue is drained before the session ends, so every file is there when pytest reports. The CPU
work then mostly overlaps the time a test waits for the device.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Any

_DONE = object()


class BackgroundWriter:
    """Runs ``write(item)`` for each submitted item on one daemon thread, in submission order."""

    def __init__(self, write: Callable[[Any], None]) -> None:
        self._write = write
        self._queue: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self._errors: list[BaseException] = []
        self._thread = threading.Thread(target=self._run, name="allure-writer", daemon=True)
        self._thread.start()

    def submit(self, item: Any) -> None:
        self._queue.put(item)

    def _run(self) -> None:
        while (item := self._queue.get()) is not _DONE:
            try:
                self._write(item)
            except Exception as exc:  # a report file must not take the run down; say so at the end
                self._errors.append(exc)

    def close(self, timeout_s: float = 30.0) -> list[BaseException]:
        """Write what is queued, stop the thread; returns the errors met (if any)."""
        self._queue.put(_DONE)
        self._thread.join(timeout_s)
        return self._errors


def write_in_background() -> BackgroundWriter | None:
    """Make allure's file logger (if one is registered) write its results on a background thread."""
    try:
        import allure_commons
        from allure_commons.logger import AllureFileLogger
    except ImportError:  # pragma: no cover - allure-pytest is a dependency
        return None
    loggers = [p for p in allure_commons.plugin_manager.get_plugins() if isinstance(p, AllureFileLogger)]
    if len(loggers) != 1:
        return None
    logger = loggers[0]
    writer = BackgroundWriter(logger._report_item)
    logger._report_item = writer.submit  # type: ignore[method-assign]  # why: replaces allure's method on purpose
    return writer
