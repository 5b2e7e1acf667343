"""Frames that come after the window that should have seen them: the ledger of "must not come" windows.

A test that proves a frame does NOT come (an SDO answer in stopped, a TPDO outside operational, a second answer)
watches a window and then moves on; a frame that comes after the window would be lost. The test declares the
window here instead (``close_sdo``, ``open_state``); the ledger (fed every frame by the FrameLog) keeps it while a
matching frame can still only be the device's answer to what provoked it, and attributes such a frame to it.

The rules are made so that a conformant device can never be blamed (DESIGN §5, "late frames"):

- an SDO request that must stay unanswered (or answered no further): a reply that answers it by content
  (``sdo_frames.answers``: command specifier, multiplexer) is attributed only where it is a surplus: no pairing of
  the replies since the window closed with the SDO requests sent since, by any master (each may draw one reply,
  CiA 301 §7.2.4: one confirmation per request, and an abort of its transfer; a pair where ``answers`` allows it,
  as the tester's own matching does; a client's abort draws none, §7.2.4.3.17) leaves it to a later request. A block
  transfer after it ends the window (its server frames carry no command specifier);
- a state in which a frame must not come (a TPDO in pre-operational or stopped, CiA 301 §7.3.2.2): from the
  device's own heartbeat reporting that state (its word that it is there; before it the device may still be
  carrying out the command) until the tester's next NMT command;
- a frame that must not come until something may allow it again (a SYNC after 1006h = 0 until 1006h is written
  other than 0, an NMT reset or the device's boot-up): from the end of the test's own window until a frame ``until``
  names, the tester's or the device's (``forbid``);
- every window ends ``HORIZON_S`` after it closed (or opened): a bound on what the ledger keeps, far beyond every
  answer window a test waits (the longest, a block sub-block's acknowledgement: the SDO transfer time-out, 1 s,
  plus the answer window).

A late frame in a moment the host itself was late (the frame's own delivery, a lateness probe started when it came,
the twin's timing thread around the window) is inconclusive, not a failure: where the host ran later than the margin
every window allows for it (``HOST_TOLERANCE_MS``) and at least as late as the frame came, the tester's view of when
the frame came, and so of which window should have seen it, is not to be trusted. (The order of frames is: the
tester logs its own before they go out, and receives the device's in bus order.)
The verdict rests on the window's clause, which forbids the frame at any time (a TPDO in stopped, an answer to a
request in stopped); that this frame is the one the window proved absent is our attribution (``LATE_RULE``): no
text says how late a forbidden frame may come.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import can

from encoder_conformance.cia.cia301 import (
    HEARTBEAT_BASE,
    SDO_REQUEST_BASE,
    SDO_RESPONSE_BASE,
    NmtCommand,
    SdoClientCommand,
)
from encoder_conformance.dut.link.latency_probe import LatencyProbe, TwinLateness
from encoder_conformance.dut.nmt.nmt_frames import is_command, target_state
from encoder_conformance.dut.sdo.sdo_frames import ABORT_SCS, BLOCK_CCS, answers

#: how long after a window closed (or a state window opened) a frame is still attributed to it (module docstring)
HORIZON_S = 5.0
#: at the end of the run the tester listens this long after the newest window closed (``linger_s``): the late faults
#: of the twin come 40-330 ms after their windows; a frame later than this after the run's last window is not seen
LINGER_S = 0.5
#: the host was late beyond this (ms): the late frame is inconclusive; the tester's margin a silence window adds for the
#: host before any measurement (``windows.UNMEASURED_MARGIN_S``; measured windows carry less: to be revisited, issue 42)
HOST_TOLERANCE_MS = 50.0  # = windows.UNMEASURED_MARGIN_S, checked by tests/test_late_frames.py (not imported: a loop)
#: how long the lateness probe started by a late frame runs (s)
PROBE_S = 0.1
#: what a late frame's verdict rests on beside the window's clause: the clause forbids the frame at any time; that this
#: frame is the one the window proved absent is our attribution (no text says how late a forbidden frame may come)
LATE_RULE = ("attributed by this suite's late-frame rules (our inference: the clause forbids the frame at any time, "
             "no text says how late it may come)")
#: the rule an SDO request in stopped breaks when answered (the tests that send one, and its late answer)
NO_SDO_IN_STOPPED = "CiA 301 §7.3.2.2 (services per NMT state: no SDO in stopped)"
#: the rule a TPDO outside operational breaks (the tests that leave operational, and a TPDO after the state shows)
NO_PDO_OUTSIDE_OPERATIONAL = "CiA 301 §7.3.2.2 (PDO communication only in operational)"
#: the NMT commands that reset the node or its communication (CiA 301 §7.3.2.2)
RESET_COMMANDS = (NmtCommand.RESET_NODE, NmtCommand.RESET_COMMUNICATION)
#: a boot-up message's one data byte (CiA 301 §7.2.8.3.2.1)
BOOT_UP = b"\x00"
#: how deep the pairing of replies with later requests searches before it counts a reply as paired (never blames)
PAIRING_DEPTH = 32  # block download and upload requests (CiA 301 §7.2.4.3.9-14)

Predicate = Callable[[can.Message], bool]
Verdict = Literal["fail", "inconclusive", "pending"]


class Owner:
    """The check that owns the windows declared now (the plugin sets the running test's node id)."""

    nodeid: str = "outside any test"


@dataclass
class Window:
    """One closed "must not come" window: what must not come, what provoked it, the clause, its owner, when it
    closed; ``attributes`` and ``sent`` carry its rule."""

    what: str
    provoked_by: str
    basis: str
    owner: str
    closed_at: float  # time.time(), the clock of frame stamps
    matches: Predicate
    ended: bool = False
    since: str = "the window closed"  # what ``closed_at`` is, in words

    def sent(self, msg: can.Message) -> None:
        """A frame after the window closed, before it is judged (a request or command may end or excuse it): the
        tester's own, or another master's."""

    def attributes(self, msg: can.Message) -> bool:
        """Is the device's frame ``msg`` the late frame this window proved absent?"""
        return self.matches(msg)


@dataclass
class SdoWindow(Window):
    """An SDO request whose window for (further) answers closed."""

    request: bytes = b""
    request_cob: int = 0
    later: list[bytes] = field(default_factory=list)  # the tester's SDO requests since the window closed
    replies: list[bytes] = field(default_factory=list)  # the replies answering ``request``, each paired with one
    paired: dict[tuple[int, bool], int] = field(default_factory=dict)  # (later request, abort?) -> reply

    def sent(self, msg: can.Message) -> None:
        if msg.arbitration_id != self.request_cob or not msg.data:
            return
        if msg.data[0] >> 5 in BLOCK_CCS:
            self.ended = True  # a block transfer's server frames cannot be paired by command specifier
        if msg.data[0] >> 5 == SdoClientCommand.ABORT:
            return  # unconfirmed (CiA 301 §7.2.4.3.17): a client's abort draws no reply a late one could be
        self.later.append(bytes(msg.data))

    def attributes(self, msg: can.Message) -> bool:
        """A reply that answers the request by content and that no pairing of the replies so far with the later
        requests (one reply each, any that ``answers`` allows) can leave to a later request: a surplus."""
        data = bytes(msg.data)
        if not self.matches(msg) or not answers(self.request, data):
            return False
        self.replies.append(data)
        if self._pair(len(self.replies) - 1, set()):
            return False
        self.replies.pop()  # the late frame: not one a later request drew
        return True

    def _pair(self, reply: int, tried: set[tuple[int, bool]], depth: int = 0) -> bool:
        """Pair ``reply`` with a later request: a free one first, newest first (a reply's own request is usually the
        last sent), else Kuhn's augmenting path, moving earlier pairs. A request may draw one answer and one abort (a
        server may abort a transfer after confirming its initiate, e.g. on its own time-out, CiA 301 §7.2.4.3.17).
        A search deeper than ``PAIRING_DEPTH`` counts as paired: the rule errs towards never blaming."""
        data = self.replies[reply]
        abort = data[0] >> 5 == ABORT_SCS
        for index in range(len(self.later) - 1, -1, -1):  # lazily: the first free one ends the search
            slot = (index, abort)
            if slot not in self.paired and answers(self.later[index], data):
                self.paired[slot] = reply
                return True
        if depth >= PAIRING_DEPTH:
            return True
        for slot in [(i, abort) for i in range(len(self.later)) if answers(self.later[i], data)]:
            if slot in tried:
                continue
            tried.add(slot)
            if self._pair(self.paired[slot], tried, depth + 1):
                self.paired[slot] = reply
                return True
        return False


@dataclass
class StateWindow(Window):
    """A state in which ``matches`` must not come: from the heartbeat reporting ``state`` to the next NMT command."""

    state: int = 0
    heartbeat_cob: int = 0
    entered: bool = False  # the device's heartbeat reported the state
    since: str = "the heartbeat reported the state"

    def sent(self, msg: can.Message) -> None:
        if is_command(msg):
            self.ended = True  # the tester's next NMT command: what follows may be the new state's

    def attributes(self, msg: can.Message) -> bool:
        if msg.arbitration_id == self.heartbeat_cob and msg.data and not self.entered:
            self.entered = msg.data[0] == self.state
            if self.entered:
                self.closed_at = msg.timestamp  # the state's start: how late is counted from here
            return False
        return self.entered and self.matches(msg)


@dataclass
class UntilWindow(Window):
    """``matches`` must not come from the window's end until a frame ``until`` names (any master's or the device's)."""

    until: Predicate = field(default=lambda m: False)

    def sent(self, msg: can.Message) -> None:
        if self.until(msg):
            self.ended = True


def writes(node_id: int, index: int, sub: int, unless: bytes | None = None) -> Predicate:
    """A frame that may change entry ``index``.``sub`` of the node: an SDO download initiate to it (any master's),
    except an expedited one of the value ``unless`` (which keeps what the window forbids forbidden)."""
    request_cob = SDO_REQUEST_BASE + node_id
    mux = bytes([index & 0xFF, index >> 8, sub])

    def changes(m: can.Message) -> bool:
        if m.arbitration_id != request_cob or len(m.data) < 8 or m.data[0] >> 5 != SdoClientCommand.INITIATE_DOWNLOAD:
            return False
        if bytes(m.data[1:4]) != mux:
            return False
        expedited = m.data[0] & 0x02
        return unless is None or not expedited or bytes(m.data[4:4 + len(unless)]) != unless
    return changes


def restarts(node_id: int) -> Predicate:
    """A frame after which the node's communication starts anew: any NMT command that resets, and its boot-up."""
    bootup_cob = HEARTBEAT_BASE + node_id
    return lambda m: ((is_command(m) and len(m.data) >= 1 and m.data[0] in RESET_COMMANDS)
                      or (m.arbitration_id == bootup_cob and bytes(m.data[:1]) == BOOT_UP))


@dataclass
class LateFrame:
    """A frame attributed to a closed window: how late, how late the host was, the verdict."""

    window: Window
    frame: can.Message
    received_at: float
    host_late_ms: float = 0.0
    host_seen: str = ""
    verdict: Verdict = "pending"
    reported: bool = False
    _probe: threading.Thread | None = field(default=None, repr=False)

    @property
    def late_ms(self) -> float:
        return (self.received_at - self.window.closed_at) * 1000

    def describe(self) -> str:
        data = "R" if self.frame.is_remote_frame else bytes(self.frame.data).hex(" ").upper()
        verdict = {"fail": "FAIL", "inconclusive": "inconclusive (the host was late)", "pending": "not judged"}
        return (f"late frame {self.frame.arbitration_id:03X}h [{data}], {self.window.what} "
                f"({self.window.provoked_by}; window owned by {self.window.owner}), {self.late_ms:.0f} ms after "
                f"{self.window.since}: "
                f"{verdict[self.verdict]}; basis: {self.window.basis}; {LATE_RULE}"
                + (f"; host: {self.host_seen}" if self.host_seen else ""))


class LateLedger:
    """The closed windows and the late frames attributed to them (fed by FrameLog under its lock)."""

    def __init__(self, twin: TwinLateness | None = None) -> None:
        self.twin = twin  # the simulated twin's own lateness, where there is one
        self._windows: list[Window] = []
        self.found: list[LateFrame] = []
        self._lock = threading.Lock()

    @property
    def watching(self) -> bool:
        return bool(self._windows)

    def close_sdo(self, node_id: int, request: bytes, provoked_by: str, basis: str) -> None:
        """The window for (further) answers to SDO ``request`` closed now."""
        response = SDO_RESPONSE_BASE + node_id
        self._add(SdoWindow(f"an answer to SDO request {request.hex(' ').upper()}", provoked_by, basis, Owner.nodeid,
                            time.time(), lambda m: m.is_rx and m.arbitration_id == response and not m.is_remote_frame,
                            request=request, request_cob=SDO_REQUEST_BASE + node_id))

    def open_state(self, node_id: int, command: str, matches: Predicate, what: str, basis: str) -> None:
        """NMT ``command`` was sent: from the heartbeat reporting the state it leads to until the next NMT command,
        ``matches`` must not come."""
        self._add(StateWindow(what, f"NMT {command}", basis, Owner.nodeid, time.time(), matches,
                              state=target_state(command),
                              heartbeat_cob=HEARTBEAT_BASE + node_id))

    def forbid(self, matches: Predicate, what: str, provoked_by: str, basis: str, until: Predicate) -> None:
        """From now, ``matches`` must not come until a frame ``until`` names (``UntilWindow``)."""
        self._add(UntilWindow(what, provoked_by, basis, Owner.nodeid, time.time(), matches, until=until))

    def linger_s(self) -> float:
        """How much longer the run should listen at its end: until ``LINGER_S`` after the newest open window closed."""
        with self._lock:
            newest = max((w.closed_at for w in self._windows if not w.ended), default=None)
        return 0.0 if newest is None else max(0.0, newest + LINGER_S - time.time())

    def _add(self, window: Window) -> None:
        with self._lock:
            self._windows.append(window)

    def on_frame(self, msg: can.Message) -> None:
        """Every frame, in bus order (the tester's own are logged before they go out)."""
        now = time.time()
        with self._lock:
            self._windows = [w for w in self._windows if not w.ended and now - w.closed_at < HORIZON_S]
            attributed = False
            for window in self._windows:  # oldest first: a frame is charged to the first window it is late for
                window.sent(msg)  # another master's request or NMT command counts as the tester's would
                if msg.is_rx and not attributed and window.attributes(msg):
                    self._found(window, msg, now)
                    attributed = True

    def _found(self, window: Window, msg: can.Message, now: float) -> None:
        late = LateFrame(window, msg, now)
        late._probe = threading.Thread(target=self._probe_host, args=(late,), name="late-frame-probe", daemon=True)
        late._probe.start()
        self.found.append(late)

    def _probe_host(self, late: LateFrame) -> None:
        """How late the host ran around the late frame: its delivery, a probe now, the twin around the window."""
        with LatencyProbe() as probe:
            threading.Event().wait(PROBE_S)  # the probe's own observation span, not a wait for the device
        lateness = probe.result()
        lag_ms = (late.received_at - late.frame.timestamp) * 1000
        lag_ms = lag_ms if 0 <= lag_ms < HORIZON_S * 1000 else 0.0  # a stamp of another clock says nothing
        twin_ms = 0.0
        if self.twin is not None:
            try:
                since = late.window.closed_at - PROBE_S  # from just before the window closed to the probe's end
                twin_ms = max((ms for when, ms in self.twin(since) if when <= late.received_at + PROBE_S),
                              default=0.0)
            except Exception:
                twin_ms = 0.0
        late.host_late_ms = max(lag_ms, lateness.worst_ms, twin_ms)
        late.host_seen = (f"frame delivered {lag_ms:.1f} ms after its stamp; {lateness.describe()}; the twin's timing "
                          f"thread up to {twin_ms:.1f} ms late around the window")
        # the host late beyond the windows' margin, and enough to have carried the frame past the window's end
        host_late = late.host_late_ms > HOST_TOLERANCE_MS and late.host_late_ms >= late.late_ms
        late.verdict = "inconclusive" if host_late else "fail"

    def judged(self, owner: str | None = None) -> list[LateFrame]:
        """The late frames not yet reported (of ``owner``, or all), judged; each marked reported."""
        with self._lock:
            taken = [late for late in self.found if not late.reported and owner in (None, late.window.owner)]
            for late in taken:
                late.reported = True
        for late in taken:
            if late._probe is not None:
                late._probe.join(PROBE_S + 2.0)
        return taken
