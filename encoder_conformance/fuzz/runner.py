"""Sends fuzz examples to the device and judges each one before the next (CiA 301 §7.2.4.3).

Per example: the requests in order (a request that owes a reply waits for one; a client's abort or a
short frame does not wait), a client's abort that closes any transfer left open, then a read of 1000h.
That read is the example's fence and liveness check at once: the device answers in order, so every
reply to the example came before the answer to 1000h, and a device that no longer answers fails there.
Heartbeat state and EMCY are checked from the frames the window holds (``watch``), the heartbeat's
continuity once per test. Once ``budget_s`` is spent, the remaining examples pass without a frame.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import can

from encoder_conformance.cia.cia301 import SDO_REQUEST_BASE, SDO_RESPONSE_BASE, SdoAbortCode
from encoder_conformance.dut import sdo_frames
from encoder_conformance.dut.device import DeviceUnderTest
from encoder_conformance.fuzz.attribution import attribute
from encoder_conformance.fuzz.oracle import Exchange, Judge, reply_required
from encoder_conformance.fuzz.strategies import Example, Request, client_abort
from encoder_conformance.fuzz.watch import DeviceWatch

FENCE = Request(sdo_frames.upload_request(0x1000, 0))
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
            if reply_required(request.frame):
                self.dut.sdo_request(request.frame)
                self.round_trips += 1
            else:
                self.dut.send_sdo(request.frame)
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

    @staticmethod
    def _closing(example: Example) -> tuple[Request, ...]:
        """An abort transfer request after any example that may have opened a transfer."""
        opening = [r for r in example if len(r.frame) == 8 and r.frame[0] >> 5 in (0, 1, 2, 3)]
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
        events = [(not m.is_rx, bytes(m.data)) for m in window if self._is_sdo(m)]
        exchanges, stray = attribute(requests, events)
        self.last_exchanges = exchanges
        problems = [f"SDO reply {r.hex(' ').upper()} before the example's first request (a late or second reply "
                    "to the example before)" for r in stray]
        problems += Judge().judge(exchanges)
        fence = exchanges[-1]
        if fence.replies and fence.replies[0][0] >> 5 != 2:
            problems.append(f"1000h no longer readable after the example: {fence.replies[0].hex(' ').upper()}")
        return problems

    def final_check(self) -> list[str]:
        """After the last example: no late SDO reply, and the heartbeat kept coming."""
        late = self.dut.frames.quiet_period(lambda m: self._is_sdo(m) and m.is_rx, self.dut.sdo_silence_s)
        problems = [f"SDO reply {bytes(m.data).hex(' ').upper()} after the last example's answers" for m in late]
        return problems + self.watch.problems() + self.watch.finish()
