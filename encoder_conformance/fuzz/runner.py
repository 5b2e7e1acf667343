"""Sends fuzz examples to the device and judges each one before the next (CiA 301 §7.2.4.3).

Per example: the requests in order, a client's abort that closes any transfer left open, then a read of 1000h.
That read is the example's fence and liveness check at once: the device answers in order, so every
reply to the example came before the answer to 1000h, and a device that no longer answers fails there.
Heartbeat state and EMCY are checked from the frames the window holds (``watch``), the heartbeat's
continuity once per test. Once ``budget_s`` is spent, the remaining examples pass without a frame.

Pairing (``attribution``): a request that owes a reply waits for it; a client's abort owes none and waits for
nothing (an answer to it is wrong wherever it goes). A frame shorter than 8 bytes may draw an abort or an answer
(open readings sdo-short-frame, sdo-short-frame-served): the next request waits until the device's time for that
frame is over (``timing.sdo_response_max_ms`` on the frames' own clock; where the interface stamps with its own
clock, plus the tester's margin), so its reply is not taken for the next request's. Replies keep their receive
stamps: on one clock a reply stamped before the next request went out is the earlier request's. The fence's answer
is the upload response: an abort naming 1000h may be the late answer to a frame before, and the fence waits once
more.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import can

from encoder_conformance.cia.cia301 import SDO_REQUEST_BASE, SDO_RESPONSE_BASE, SdoAbortCode
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.sdo import sdo_frames, sdo_words
from encoder_conformance.dut.sdo.sdo_words import Stamped
from encoder_conformance.fuzz.attribution import attribute
from encoder_conformance.fuzz.oracle import Exchange, Judge, reply_required
from encoder_conformance.fuzz.strategies import Example, Request, client_abort
from encoder_conformance.fuzz.watch import DeviceWatch

FENCE = Request(sdo_frames.upload_request(0x1000, 0))
#: how far a reply's stamp may lie outside the example (before its first request, after now) on one clock
CLOCK_SLACK_S = 1.0
#: the code of the closing abort: "SDO protocol timed out" (CiA 301 §7.2.4.3.17), the client gives up
CLOSING_ABORT_CODE = SdoAbortCode.TIMEOUT


@dataclass
class Failure:
    """The first failing example: what was sent and what the bus showed, for the replay."""

    requests: tuple[Request, ...]
    problems: list[str]
    window: list[can.Message]
    before: list[can.Message]


@dataclass
class FuzzRunner:
    dut: DeviceUnderTest
    watch: DeviceWatch
    budget_s: float | None = None
    started: float = field(default_factory=time.monotonic)
    examples: int = 0
    exchanges: int = 0  # request frames sent, each judged with what it drew (the 1000h reads included)
    round_trips: int = 0  # of which requests that owed a reply and were waited for
    busy_s: float = 0.0  # time spent sending examples
    skipped: int = 0  # examples after the budget was spent
    failure: Failure | None = None
    first_emcy: Failure | None = None  # the example after which the first EMCY came (a warning, not a failure)
    last_exchanges: list[Exchange] = field(default_factory=list)  # the last example's, for checks of a test
    _before: list[can.Message] = field(default_factory=list)
    _clocks_differ: bool = False  # a reply's stamp lay off the tester's clock (see ``stamped``)

    @property
    def spent(self) -> bool:
        return self.budget_s is not None and time.monotonic() - self.started >= self.budget_s

    @property
    def rate(self) -> float:
        """Exchanges per second while sending (hypothesis's own time between examples not counted)."""
        return self.exchanges / self.busy_s if self.busy_s else 0.0

    @property
    def wall_rate(self) -> float:
        """Exchanges per second of the test's wall-clock so far (example generation included)."""
        elapsed = time.monotonic() - self.started
        return self.exchanges / elapsed if elapsed else 0.0

    def run(self, example: Example) -> list[str]:
        """Send ``example`` and judge it; the problems found (empty: it passed)."""
        if self.spent:
            self.skipped += 1
            return []
        begun = time.monotonic()
        requests = (*example, *self._closing(example), FENCE)
        mark = self.dut.frames.mark()
        for request in requests:
            if request is FENCE:
                self._fence()
            elif reply_required(request.frame):
                self.dut.sdo_request(request.frame)
            elif len(request.frame) < 8:
                self._short_frame_window(self.dut.send_sdo(request.frame))
            else:
                self.dut.send_sdo(request.frame)
            self.round_trips += reply_required(request.frame)
            self.exchanges += 1
        self.examples += 1
        window = self.dut.frames.since(mark, self._is_sdo_or_watched)
        emcy_before = len(self.watch.emcy)
        problems = self._judge(requests, window) + self.watch.problems()
        self.busy_s += time.monotonic() - begun
        if problems and self.failure is None:
            self.failure = Failure(requests, problems, window, self._before)
        if len(self.watch.emcy) > emcy_before and self.first_emcy is None:
            self.first_emcy = Failure(requests, [f"EMCY {bytes(self.watch.emcy[emcy_before].data).hex(' ').upper()}"],
                                      window, self._before)
        self._before = window
        return problems

    @property
    def stamped(self) -> bool:
        """The frames' timestamps are of the tester's clock (host or kernel), so they order requests and replies:
        not where the adapter stamps with its own, nor once a reply's stamp lay off the tester's clock."""
        return not self.dut.frames.clock.hardware and not self._clocks_differ

    def _check_clock(self, window: list[can.Message]) -> None:
        """A reply stamped over ``CLOCK_SLACK_S`` before the example's first request or after now: another clock
        (a remote bus stamping with its adapter's); from then on the log's order alone pairs the frames."""
        sent = [m.timestamp for m in window if not m.is_rx]
        now = time.time()
        if sent and any(not sent[0] - CLOCK_SLACK_S <= m.timestamp <= now + CLOCK_SLACK_S
                        for m in window if m.is_rx):
            self._clocks_differ = True

    def _short_frame_window(self, sent: Mark) -> None:
        """Watch for the answer a frame under 8 bytes may draw, for as long as the device has for it (see the
        module docstring); it ends early where the answer comes."""
        owed_s = self.dut.profile.timing.sdo_response_max_ms / 1000
        window = owed_s if self.stamped else self.dut.sdo_silence_s
        own = self.dut.frames.since(sent, lambda m: not m.is_rx and self._is_sdo(m))
        at = own[0].timestamp if own and self.stamped else None
        self.dut.frames.wait_for(lambda m: self._is_reply(m) and (at is None or m.timestamp >= at), window, after=sent)

    def _fence(self) -> None:
        """Read 1000h; where an abort naming it comes first, wait for what the device owes a read once more: the
        abort may answer a frame before (a short one, naming the last multiplexer it served)."""
        mark = self.dut.frames.mark()
        reply = self.dut.sdo_request(FENCE.frame)
        if reply is not None and reply.is_abort:
            self.dut.frames.wait_for(lambda m: self._is_reply(m) and m.data[0] >> 5 == 2, self.dut.sdo_timeout,
                                     after=mark)  # the read's answer is owed: the answer window, ended when it comes

    def _is_reply(self, msg: can.Message) -> bool:
        return msg.is_rx and self._is_sdo(msg)

    @staticmethod
    def _closing(example: Example) -> tuple[Request, ...]:
        """An abort transfer request after any example that may have opened a transfer (a frame under 8 bytes that
        carries an initiate's multiplexer too: it may have been served)."""
        opening = [r for r in example if (len(r.frame) == 8 and r.frame[0] >> 5 in (0, 1, 2, 3))
                   or (len(r.frame) >= 4 and r.frame[0] >> 5 in (1, 2))]
        if not opening:
            return ()
        mux = sdo_frames.SdoResponse(opening[-1].frame)
        return (client_abort((mux.index, mux.sub), CLOSING_ABORT_CODE),)

    def _is_sdo(self, msg: can.Message) -> bool:
        expected = SDO_RESPONSE_BASE if msg.is_rx else SDO_REQUEST_BASE
        return not msg.is_remote_frame and msg.arbitration_id == expected + self.dut.node_id

    def _is_sdo_or_watched(self, msg: can.Message) -> bool:
        return self._is_sdo(msg) or self.dut.is_heartbeat(msg) or (msg.is_rx and msg.arbitration_id ==
                                                                   self.watch.emcy_cob_id)

    def _judge(self, requests: tuple[Request, ...], window: list[can.Message]) -> list[str]:
        self._check_clock(window)
        events = [(not m.is_rx, Stamped(bytes(m.data), m.timestamp)) for m in window if self._is_sdo(m)]
        exchanges, stray = attribute(requests, events, self.stamped)
        self.last_exchanges = exchanges
        problems = [f"SDO reply {sdo_words.reply(r)} ({r.hex(' ').upper()}) before the example's first request (a "
                    "late or second reply to the example before)" for r in stray]
        problems += Judge().judge(exchanges)
        fence = exchanges[-1]
        if fence.replies and fence.replies[0][0] >> 5 != 2:
            problems.append(f"1000h no longer readable after the example: {sdo_words.replies(fence.replies)}")
        return problems

    def final_check(self) -> list[str]:
        """After the last example: no late SDO reply, and the heartbeat kept coming."""
        late = self.dut.frames.quiet_period(lambda m: self._is_sdo(m) and m.is_rx, self.dut.sdo_silence_s)
        problems = [f"SDO reply {bytes(m.data).hex(' ').upper()} after the last example's answers" for m in late]
        return problems + self.watch.problems() + self.watch.finish()
