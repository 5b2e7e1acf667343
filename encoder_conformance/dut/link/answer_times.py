"""What this device answers in, measured: SDO expedited round trips taken once at the start of a run, with the
host's own lateness during them (``LatencyProbe``, the twin's too where there is one).

Two figures per round trip: ``seen``, the tester's request to the moment the waiting thread had the answer (what a
window must cover: a frame that reaches the tester after the window closed is not in it), and ``stamped``, the
request's stamp to the answer's (the device's own time, as the frame clock shows it: ``dut/link/clock.py``; on a
twin or a host-stamped adapter both are the host clock). The windows (``dut/link/windows.py``) are sized from
``seen``; ``stamped`` is evidence.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from encoder_conformance.cia.cia301 import SDO_RESPONSE_BASE
from encoder_conformance.dut.link.latency_probe import HostLatency, LatencyProbe, TwinLateness
from encoder_conformance.dut.sdo.sdo_frames import SdoResponse, upload_request
from encoder_conformance.models.timing import percentile

if TYPE_CHECKING:  # frames -> late_frames -> windows -> here: a type only
    from encoder_conformance.dut.link.frames import FrameLog

#: round trips measured at the start: 30 give a p99 that is the worst but one of them (statistics.quantiles
#: inclusive), and cost ~30 x 1 ms on a device answering within 1 ms
SDO_SAMPLES = 30
#: the object read: 1000h (device type), mandatory on every CANopen device and read-only
PROBE_OBJECT = (0x1000, 0)


class SdoLink(Protocol):
    """What the measurement needs of ``DeviceLink`` (not imported: the link imports the windows sized from this)."""

    frames: FrameLog
    node_id: int

    def sdo_request(self, request: bytes, check_alive: bool = True,
                    timeout: float | None = None) -> SdoResponse | None: ...


@dataclass(frozen=True)
class AnswerTimes:
    """Round trips of one kind of request (milliseconds), and the host's lateness while they were taken."""

    what: str
    seen_ms: tuple[float, ...]
    stamped_ms: tuple[float, ...]
    host: HostLatency
    unanswered: int = 0

    @property
    def p50_ms(self) -> float:
        return percentile(list(self.seen_ms), 0.5)

    @property
    def p99_ms(self) -> float:
        return percentile(list(self.seen_ms), 0.99)

    @property
    def max_ms(self) -> float:
        return max(self.seen_ms)

    @property
    def host_late_ms(self) -> float:
        """The host's worst lateness during the measurement: the tester's timer, and the twin's where there is one."""
        return max(self.host.worst_ms, self.host.twin_worst_ms or 0.0)

    def evidence(self) -> dict[str, Any]:
        """The measurement as run-summary.json keeps it."""
        stamped = list(self.stamped_ms)
        return {
            "what": self.what, "samples": len(self.seen_ms), "unanswered": self.unanswered,
            "p50_ms": round(self.p50_ms, 3), "p99_ms": round(self.p99_ms, 3), "max_ms": round(self.max_ms, 3),
            "stamped_p50_ms": round(percentile(stamped, 0.5), 3) if stamped else None,
            "stamped_max_ms": round(max(stamped), 3) if stamped else None,
            "host_late_ms": round(self.host.worst_ms, 3), "host_late_p95_ms": round(self.host.p95_ms, 3),
            "twin_late_ms": None if self.host.twin_worst_ms is None else round(self.host.twin_worst_ms, 3),
        }

    def describe(self) -> str:
        return (f"{self.what}: p50 {self.p50_ms:.2f} ms, p99 {self.p99_ms:.2f} ms, max {self.max_ms:.2f} ms over "
                f"{len(self.seen_ms)} round trips; {self.host.describe()}")


def measure_sdo(link: SdoLink, samples: int = SDO_SAMPLES, twin: TwinLateness | None = None) -> AnswerTimes | None:
    """``samples`` expedited uploads of 1000h through ``link`` (a ``DeviceLink``), each waited for its answer
    window (the link's SDO time-out); None where fewer than half were answered (nothing to size a window from)."""
    seen: list[float] = []
    stamped: list[float] = []
    missed = 0
    request = upload_request(*PROBE_OBJECT)
    with LatencyProbe(twin) as probe:
        for _ in range(samples):
            mark = link.frames.mark()
            started = time.perf_counter()
            reply = link.sdo_request(request, check_alive=False)
            if reply is None:
                missed += 1
                if missed * 2 >= samples:  # too few left to size from: no more time-outs spent on it
                    break
                continue
            seen.append((time.perf_counter() - started) * 1000)
            frames = link.frames.since(mark)
            sent = next((m for m in frames if not m.is_rx), None)
            answer = next((m for m in frames if m.is_rx and m.arbitration_id == SDO_RESPONSE_BASE + link.node_id), None)
            if sent is not None and answer is not None:
                stamped.append(max(0.0, (answer.timestamp - sent.timestamp) * 1000))
    if missed * 2 >= samples:
        return None
    return AnswerTimes(f"SDO expedited upload {PROBE_OBJECT[0]:04X}h", tuple(seen), tuple(stamped), probe.result(),
                       missed)
