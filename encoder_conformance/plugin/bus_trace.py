"""A test's bus trace, held in memory until its verdict says whether it is kept.

With ``--trace failed`` (the default) only failed, errored and warned tests keep their trace, about one
test in ten on a failing device and none on a conformant one. Writing every test's ASC and candump files as
the frames arrived, then deleting most of them, cost each test two files opened, written, closed and deleted,
and each frame two formatted lines under the frame log's lock (on the way to the test waiting for it): about
0.5 s of a WDGA run. Here a frame is only appended to a list; the files are written by python-can's writers
once the test's last phase is judged (reporting.settle_trace), with the same content: the ASC header's date
is the time the trace began, as when it was written live.

A trace whose test never reached its teardown report (Ctrl-C, SIGTERM, a stop inside the test) is written at
the session's end (``write_unsettled``), as its files used to stay. Only a process killed outright (SIGKILL, a
crash of the interpreter) loses the trace of the test it was running.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

import can
import pytest

from encoder_conformance.dut.link.frames import FrameLog, Mark

_UNSETTLED = pytest.StashKey[dict[int, "BusTrace"]]()
#: the run's frame log (set by the evidence fixture) and where each test's set-up starts in it
FRAME_LOG = pytest.StashKey[FrameLog]()
SET_UP_FROM = pytest.StashKey[Mark]()


def mark_set_up_start(item: pytest.Item) -> None:
    """Where the test's set-up starts in the frame log: the frames its fixtures send before the trace opens
    (session fixtures such as the periodic capture, the start-up check of the first test) belong in its trace."""
    frames = item.config.stash.get(FRAME_LOG, None)
    item.stash[SET_UP_FROM] = frames.mark() if frames is not None else Mark(0, 0.0)


class _AscWriter(can.ASCWriter):
    """python-can's ASC writer, with the header's date given (the trace's start) instead of 'now'."""

    def __init__(self, file: str, date: datetime) -> None:
        self._date: datetime | None = date
        super().__init__(file)

    def _format_header_datetime(self, dt: datetime) -> str:
        if self._date is not None:  # the first call: the header's 'date' line
            dt, self._date = self._date, None
        return super()._format_header_datetime(dt)


class BusTrace(can.Listener):
    """The frames of one test, in order (a frame log listener); ``write`` puts them in traces/<test>.asc/.log."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.began = datetime.now()
        self.frames: list[can.Message] = []
        self.written = False

    def on_message_received(self, msg: can.Message) -> None:
        self.frames.append(msg)

    def write(self) -> None:
        """The ASC (Vector) and candump log files, once."""
        if self.written:
            return
        self.written = True
        self.path.parent.mkdir(parents=True, exist_ok=True)
        asc = _AscWriter(str(self.path), self.began)
        log = can.CanutilsLogWriter(str(self.path.with_suffix(".log")))
        try:
            for msg in self.frames:
                asc.on_message_received(msg)
                log.on_message_received(msg)
        finally:
            asc.stop()
            log.stop()


def opened(config: pytest.Config, trace: BusTrace) -> None:
    """A test's trace has begun: it is written at the session's end unless settled before."""
    config.stash.setdefault(_UNSETTLED, {})[id(trace)] = trace


def settle(config: pytest.Config, trace: BusTrace, keep: bool) -> None:
    """The test's last phase is judged: write its trace if kept, else let the frames go."""
    config.stash.get(_UNSETTLED, {}).pop(id(trace), None)
    if keep:
        trace.write()
    trace.frames = []


def write_unsettled(config: pytest.Config) -> None:
    """At the session's end: the traces of tests that never got their teardown report are kept."""
    for trace in config.stash.get(_UNSETTLED, {}).values():
        trace.write()
    config.stash[_UNSETTLED] = {}
