"""Every frame on the bus, in order, with event waits (no fixed sleeps anywhere).

One FrameLog listens on the tester's bus and also records the tester's own transmissions
(through TracingBus), so traces show both directions. Waits block on a condition variable
until a matching frame arrives or the timeout expires. When the bus is lost (``close``), every
wait raises BusLostError at once: a dead bus must not look like a silent device.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import can

from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.link.clock import FrameClock
from encoder_conformance.dut.link.late_frames import LateLedger
from encoder_conformance.dut.link.time_budget import BUDGET
from encoder_conformance.errors import BusLostError

log = logging.getLogger(__name__)

Predicate = Callable[[can.Message], bool]


@dataclass(frozen=True)
class Mark:
    """A position in the log: 'frames after this point'."""

    seq: int
    time: float


class FrameLog(can.Listener):
    """Thread-safe, bounded log of frames with waits."""

    def __init__(self, keep: int = 20000) -> None:
        self._frames: deque[tuple[int, can.Message]] = deque(maxlen=keep)
        self._seq = 0
        self._cond = threading.Condition()
        self._listeners: list[can.Listener] = []
        self.closed_reason: str | None = None
        #: what stamps the frames (set where the bus is opened): timing verdicts say which clock judged
        self.clock = FrameClock("not known (the bus was opened without saying which clock stamps it)", False)
        #: the closed "must not come" windows: a frame after its window is still attributed (late_frames.py)
        self.late = LateLedger()

    def close(self, reason: str) -> None:
        """The bus is gone: wake every wait (they raise BusLostError from now on)."""
        with self._cond:
            self.closed_reason = self.closed_reason or reason
            self._cond.notify_all()

    def on_error(self, exc: Exception) -> None:
        """python-can Listener hook: the interface failed while receiving."""
        self.close(f"the CAN bus failed on receive: {type(exc).__name__}: {exc}")

    def _raise_if_closed(self) -> None:
        if self.closed_reason:
            raise BusLostError(self.closed_reason)

    # can.Listener
    def on_message_received(self, msg: can.Message) -> None:
        # listeners (the per-test trace writers) run under the lock, before the waiters wake: a test that
        # has its answer finds it in its trace, and a writer removed at teardown is never called after
        # (outside the lock, the receive thread wrote into a closed trace file, which ended the run as a
        # "lost bus" on a loaded machine)
        with self._cond:
            self._seq += 1
            self._frames.append((self._seq, msg))
            if self.late.watching:
                self.late.on_frame(msg)
            for listener in self._listeners:
                try:
                    listener.on_message_received(msg)
                except Exception as exc:  # a trace that cannot be written is not a lost bus
                    log.warning("frame listener %r failed: %s", listener, exc)
            self._cond.notify_all()

    def record_sent(self, msg: can.Message, channel: str | int | None = None) -> None:
        """Called by TracingBus for the tester's own frames; ``channel``: the bus's, where the frame names none."""
        copy = can.Message(
            timestamp=time.time(),
            arbitration_id=msg.arbitration_id,
            is_extended_id=msg.is_extended_id,
            is_remote_frame=msg.is_remote_frame,
            dlc=msg.dlc,
            data=msg.data,
            is_rx=False,
            channel=msg.channel if msg.channel is not None else channel,
        )
        self.on_message_received(copy)

    def add_listener(self, listener: can.Listener, replay_from: Mark | None = None) -> None:
        """``listener`` gets every frame from now on; with ``replay_from``, first the frames since that mark still
        in the log (at once, under the lock: none is missed or given twice)."""
        with self._cond:
            if replay_from is not None:
                for msg in self._after(replay_from.seq):
                    listener.on_message_received(msg)
            self._listeners.append(listener)

    def remove_listener(self, listener: can.Listener) -> None:
        with self._cond:
            if listener in self._listeners:
                self._listeners.remove(listener)

    def mark(self) -> Mark:
        with self._cond:
            return Mark(self._seq, time.monotonic())

    def since(self, mark: Mark, predicate: Predicate | None = None) -> list[can.Message]:
        with self._cond:
            return [m for m in self._after(mark.seq) if predicate is None or predicate(m)]

    def _after(self, seq: int) -> list[can.Message]:
        """The frames after sequence number ``seq``, read from the end of the log (call with the lock held):
        a wait looks only at what arrived since it last looked, never at the whole log again."""
        frames = self._frames
        count = min(self._seq - seq, len(frames))
        return [frames[i][1] for i in range(len(frames) - count, len(frames))] if count > 0 else []

    def before(self, mark: Mark, predicate: Predicate, count: int = 200) -> list[can.Message]:
        """The frames ``predicate`` matches among the ``count`` frames up to ``mark``, oldest first."""
        with self._cond:
            frames = self._frames
            end = len(frames) - min(self._seq - mark.seq, len(frames))
            return [m for _, m in (frames[i] for i in range(max(0, end - count), end)) if predicate(m)]

    def last(self, count: int = 20) -> list[can.Message]:
        with self._cond:
            return [m for _, m in list(self._frames)[-count:]]

    def wait_for(self, predicate: Predicate, timeout: float, after: Mark | None = None) -> can.Message | None:
        """First frame after ``after`` (default: now) matching ``predicate``, or None on timeout."""
        hits = self.wait_count(predicate, 1, timeout, after)
        return hits[0] if hits else None

    def wait_count(
        self, predicate: Predicate, count: int, timeout: float, after: Mark | None = None
    ) -> list[can.Message]:
        """Up to ``count`` matching frames after ``after``; returns early once ``count`` are seen."""
        start = after or self.mark()
        deadline = Deadline(timeout)
        hits: list[can.Message] = []
        with BUDGET.booking("periodic" if count > 1 else "answer") as booking, self._cond:
            seen = start.seq
            while True:
                self._raise_if_closed()
                hits += [m for m in self._after(seen) if predicate(m)]
                seen = self._seq
                if len(hits) >= count or deadline.expired():
                    if len(hits) < count and count == 1:
                        booking.category = "silence"  # nothing came: the whole window was owed
                    return hits[:count]
                self._cond.wait(deadline.remaining())

    def quiet_period(self, predicate: Predicate, duration: float, after: Mark | None = None) -> list[can.Message]:
        """Frames matching ``predicate`` within ``duration`` s (an observation window, not a sleep)."""
        start = after or self.mark()
        deadline = Deadline(duration)
        with BUDGET.booking("silence"), self._cond:
            while not deadline.expired():
                self._raise_if_closed()
                self._cond.wait(deadline.remaining())
            self._raise_if_closed()
            return [m for m in self._after(start.seq) if predicate(m)]


def format_frames(frames: list[can.Message]) -> str:
    """candump-like lines for failure messages."""
    lines = []
    for msg in frames:
        direction = "Rx" if msg.is_rx else "Tx"
        data = "R" if msg.is_remote_frame else msg.data.hex(" ").upper()
        lines.append(f"  {msg.timestamp:.4f} {direction} {msg.arbitration_id:03X} [{msg.dlc}] {data}")
    return "\n".join(lines)


def received_on(can_id: int) -> Predicate:
    """The data frames received on ``can_id`` (a TPDO's, a SYNC producer's): not the tester's own, not a remote
    request."""
    return lambda m: m.is_rx and m.arbitration_id == can_id and not m.is_remote_frame
