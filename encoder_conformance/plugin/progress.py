"""Live progress of a run on a terminal: one line that updates in place (area, test n of N, elapsed,
estimated remaining, failures so far), and a FAILED line above it as soon as a test fails.

Shown only where a person watches: stdout is a terminal, the environment variable CI is not set, neither
``-q`` nor ``-v`` was given (-v already prints a line per test), ``ENCODER_CONFORMANCE_PROGRESS`` is not
``0``, and only once the run has taken ``SHOW_AFTER_S`` (a short run ends before it would be read;
``ENCODER_CONFORMANCE_PROGRESS=always`` shows it from the first test, still only on a terminal). In
that mode pytest's dots and file names are left out (the line replaces them); the summary at the end is
pytest's own.

The line is written to a duplicate of the terminal's file descriptor taken before any test runs, by a
timer thread as well as at each test's start and end. So it never lands in a test's captured output,
in the junit/HTML report, or in a log file: pytest redirects fd 1 while a test runs, the duplicate still
points at the terminal. Hand-written (about 150 lines) because pytest-sugar replaces the whole terminal
reporter and pytest-rich/enlighten would add a dependency for one line.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable, Generator
from dataclasses import dataclass

import pytest

from encoder_conformance.plugin.activation import runs_suites
from encoder_conformance.run_summary import area_of

ENV_SWITCH = "ENCODER_CONFORMANCE_PROGRESS"
SHOW_AFTER_S = 2.0
REDRAW_S = 0.5
CLEAR = "\r\x1b[K"

def wanted(config: pytest.Config, isatty: bool, environ: dict[str, str] | os._Environ[str]) -> bool:
    """Whether this run shows the live line."""
    if environ.get("CI") or environ.get(ENV_SWITCH) == "0" or not isatty:
        return False
    if config.get_verbosity() != 0 or hasattr(config, "workerinput"):
        return False
    return config.pluginmanager.get_plugin("terminalreporter") is not None and runs_suites(config)


def clock_text(seconds: float) -> str:
    """'1:05', '1:02:03'."""
    minutes, secs = divmod(int(seconds + 0.5), 60)
    return f"{minutes // 60}:{minutes % 60:02d}:{secs:02d}" if minutes >= 60 else f"{minutes}:{secs:02d}"


@dataclass
class Tally:
    """Where the run is: what the line shows."""

    total: int = 0
    started: int = 0  # tests started, the current one included
    finished: int = 0
    area: str = ""
    failed: int = 0
    warnings: int = 0
    skipped: int = 0

    def remaining_s(self, testing_s: float) -> float | None:
        """From the mean time of the tests so far (``testing_s`` since the first began); None until three
        tests have ended."""
        if self.finished < 3 or self.total <= self.finished:
            return None
        return testing_s / self.finished * (self.total - self.finished)


def format_line(tally: Tally, elapsed_s: float, width: int, testing_s: float | None = None) -> str:
    """'PDO  test 123 of 456  1:23 elapsed  ~2:10 left  2 failed, 1 warnings', cut to the terminal's width.
    ``elapsed_s`` counts from the start of the run, ``testing_s`` from the first test (the estimate's base:
    collection and the device snapshot are no test time)."""
    parts = [tally.area or "starting", f"test {tally.started} of {tally.total}", f"{clock_text(elapsed_s)} elapsed"]
    remaining = tally.remaining_s(elapsed_s if testing_s is None else testing_s)
    parts.append(f"~{clock_text(remaining)} left" if remaining is not None else "estimating")
    counts = [f"{n} {word}" for n, word in ((tally.failed, "failed"), (tally.warnings, "warnings"),
                                            (tally.skipped, "skipped")) if n]
    if counts:
        parts.append(", ".join(counts))
    line = "  ".join(parts)
    return line if len(line) < width else line[: max(width - 2, 0)] + "…"


class LiveProgress:
    """The line and the thread that keeps its clock running."""

    def __init__(self, fd: int, width: Callable[[], int], clock: Callable[[], float] = time.monotonic,
                 show_after_s: float = SHOW_AFTER_S) -> None:
        self._fd = fd
        self._show_after_s = show_after_s
        self._width = width
        self._clock = clock
        self._start = clock()
        self._first_test: float | None = None
        self._lock = threading.Lock()
        self._shown = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.tally = Tally()

    def begin(self, total: int) -> None:
        self.tally.total = total
        self._thread = threading.Thread(target=self._tick, name="live-progress", daemon=True)
        self._thread.start()

    def test_started(self, nodeid: str) -> None:
        if self._first_test is None:
            self._first_test = self._clock()
        self.tally.started += 1
        self.tally.area = area_of(nodeid)
        self.draw()

    def test_reported(self, report: pytest.TestReport) -> None:
        if report.failed:
            self.tally.failed += 1
            self._line_above(f"FAILED {report.nodeid}" + ("" if report.when == "call" else f" ({report.when})"))
        elif ("verdict", "warning") in report.user_properties:  # plugin/verdicts.py: an inferred rule broken
            self.tally.warnings += 1
        elif report.skipped:
            self.tally.skipped += 1

    def test_finished(self) -> None:
        self.tally.finished += 1
        self.draw()

    def draw(self, force: bool = False) -> None:
        now = self._clock()
        elapsed = now - self._start
        if not force and elapsed < self._show_after_s:
            return
        testing = None if self._first_test is None else now - self._first_test
        with self._lock:
            if self._stop.is_set():
                return
            self._write(CLEAR + format_line(self.tally, elapsed, self._width(), testing))
            self._shown = True

    def close(self) -> None:
        """Erase the line (the summary follows) and stop the clock."""
        with self._lock:
            self._stop.set()
            if self._shown:
                self._write(CLEAR)
                self._shown = False
        os.close(self._fd)

    def _line_above(self, text: str) -> None:
        with self._lock:
            self._write(CLEAR + text + "\n")
        self.draw(force=self._shown)

    def _tick(self) -> None:
        while not self._stop.wait(REDRAW_S):
            self.draw()

    def _write(self, text: str) -> None:
        try:
            os.write(self._fd, text.encode(errors="replace"))
        except OSError:  # the terminal went away: the run goes on without its line
            self._stop.set()


# -- pytest hooks ------------------------------------------------------------------------------------
@pytest.hookimpl(trylast=True)
def pytest_configure(config: pytest.Config) -> None:
    """Registers the live line for this run where it is wanted (conftest.py lists this module)."""
    if not wanted(config, sys.stdout.isatty(), os.environ):
        return
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is None:  # -p no:terminal: no terminal output to draw the line in
        return
    reporter.showfspath = False  # the line replaces 'suites/test_x.py ....'
    writer = config.get_terminal_writer()
    show_after_s = 0.0 if os.environ.get(ENV_SWITCH) == "always" else SHOW_AFTER_S
    live = LiveProgress(os.dup(sys.stdout.fileno()), lambda: writer.fullwidth, show_after_s=show_after_s)
    config.pluginmanager.register(ProgressHooks(live), "encoder-conformance-progress")


class ProgressHooks:
    """The hooks of one run with a live line."""

    def __init__(self, live: LiveProgress) -> None:
        self.live: LiveProgress | None = live

    def pytest_collection_finish(self, session: pytest.Session) -> None:
        if self.live is not None:
            self.live.begin(len(session.items))

    def pytest_runtest_logstart(self, nodeid: str) -> None:
        if self.live is not None:
            self.live.test_started(nodeid)

    def pytest_runtest_logfinish(self) -> None:
        if self.live is not None:
            self.live.test_finished()

    @pytest.hookimpl(wrapper=True)
    def pytest_report_teststatus(self, report: pytest.TestReport) -> Generator[None, tuple, tuple]:
        """pytest's letter ('.', 's', 'F') left out while the line shows; the category still counts."""
        status = yield
        if self.live is None or not status:
            return status
        category, letter, word = status
        if letter or word:  # the phase that decides the test's outcome
            self.live.test_reported(report)
        return category, "", ""

    @pytest.hookimpl(wrapper=True)
    def pytest_runtestloop(self) -> Generator[None, object, object]:
        """The line goes when the tests end (also on Ctrl-C), before the restore's and pytest's summary."""
        try:
            return (yield)
        finally:
            if self.live is not None:
                self.live.close()
                self.live = None
