"""How long the tester watches for a frame the device must NOT send (a silence window), sized from what this device
was measured to answer in (``dut/link/answer_times.py``), the host's measured lateness and the bounds its manual
gives; each window is kept with the figure it came from, for the evidence (run-summary.json ``time_budget.windows``).

A measured kind (SDO: round trips at the start of the run) is watched for the largest of:
  - ``FACTOR`` x the device's measured p99 (request to the answer in the tester's hands),
  - the host's worst lateness during the measurement (the tester's timer, the twin's where there is one),
  - the figure the profile says a manual documents (``Timing.documented``): a promise, never waited less.
A kind not measured yet (PDO, EMCY, LSS) is watched for what the profile says the device owes (documented or the
suite's default) plus the tester's part: the largest of ``FACTOR`` x the measured SDO p99 (the round trip bounds
the bus hop and the host both ways) and the host's lateness; before any measurement (the start-up check itself)
the tester's part is ``UNMEASURED_MARGIN_S``. An expected answer is waited for ``answer_window`` (the wait ends when
it comes), unchanged: a silence window never sizes a wait for a frame that must come (``DeviceLink.pdo_answer_s``,
``sdo_timeout``), so a short one loses no frame the device owes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from encoder_conformance.dut.link.answer_times import AnswerTimes
from encoder_conformance.models.timing import percentile
from encoder_conformance.profile.schema import Timing

#: a window is this many times the device's measured p99 round trip. The spread measured on the twins (DESIGN.md
#: §8, "Wait only for what the device owes"): the p99 of ~1000 later round trips was up to 3.9 x the start p99 idle
#: and 6.2 x under a busy process; 10 covers both with room (rarer single stalls are the late-frame ledger's)
FACTOR = 10.0
#: the tester's part where nothing was measured yet (the start-up check's probes, a measurement that failed):
#: SDO round trips to the twin measured p99 < 20 ms on the 2-core CI machine with two runs and a busy process
#: beside them; 50 ms leaves room (the margin every silence window had before windows were measured)
UNMEASURED_MARGIN_S = 0.05
#: answers of a kind seen in the run before its window is sized from them (LSS answers, observed where the suite
#: first exchanges them); with 5, the p99 is their slowest
MIN_OBSERVED = 5
#: the timing figures a silence window is watched for (every one is in the evidence, used or not)
SILENCE_FIGURES = ("sdo_response_max_ms", "pdo_response_max_ms", "emcy_response_max_ms", "lss_response_ms")


@dataclass(frozen=True)
class Window:
    """One silence window: its name (the timing figure of what must not come), its length and where it came from."""

    name: str
    seconds: float
    source: str

    def evidence(self) -> dict[str, Any]:
        return {"name": self.name, "seconds": round(self.seconds, 4), "source": self.source}


class Windows:
    """The silence windows of one device, from its profile and, once taken, its measured answer times."""

    def __init__(self, timing: Timing) -> None:
        self.timing = timing
        self.sdo: AnswerTimes | None = None
        self._observed: dict[str, list[float]] = {}
        self._cache: dict[str, Window] = {}

    def measured(self, sdo: AnswerTimes | None) -> None:
        """The start-of-run measurement (None: it failed; the windows stay the profile's plus the margin)."""
        self.sdo = sdo
        self._cache.clear()

    def observe(self, figure: str, ms: float) -> None:
        """An answer of the kind ``figure`` bounds came ``ms`` after its request (as the tester saw it)."""
        samples = self._observed.setdefault(figure, [])
        samples.append(ms)
        if len(samples) >= MIN_OBSERVED:
            self._cache.pop(figure, None)

    def silence(self, figure: str) -> Window:
        """The silence window for what the profile's timing ``figure`` (e.g. ``sdo_response_max_ms``) bounds."""
        window = self._cache.get(figure)
        if window is None:
            window = self._cache[figure] = self._size(figure)
        return window

    def silence_s(self, figure: str) -> float:
        return self.silence(figure).seconds

    def evidence(self) -> list[dict[str, Any]]:
        """Every silence window (those of ``SILENCE_FIGURES`` and any other sized), with its source."""
        for figure in SILENCE_FIGURES:
            self.silence(figure)
        return [w.evidence() for _, w in sorted(self._cache.items())]

    def _size(self, figure: str) -> Window:
        owed_ms = float(getattr(self.timing, figure))
        documented = self.timing.documented.get(figure)
        owed = f"{figure} {owed_ms:g} ms ({f'documented: {documented}' if documented else 'suite default'})"
        if self.sdo is None:
            return Window(figure, owed_ms / 1000 + UNMEASURED_MARGIN_S,
                          f"{owed} + unmeasured tester margin {UNMEASURED_MARGIN_S * 1000:g} ms (no measurement)")
        late_ms = self.sdo.host_late_ms
        measured = self._measured(figure)
        if measured is None:
            spread_ms = FACTOR * self.sdo.p99_ms
            return Window(figure, (owed_ms + max(spread_ms, late_ms)) / 1000,
                          f"{owed}, not measured, + tester's part: largest of {FACTOR:g} x measured SDO p99 "
                          f"{self.sdo.p99_ms:.2f} ms = {spread_ms:.2f} ms, host lateness {late_ms:.2f} ms")
        what, p99_ms = measured
        spread_ms = FACTOR * p99_ms
        floor_ms = owed_ms if documented else 0.0
        floor = f", documented floor {owed_ms:g} ms ({documented})" if documented else f" ({owed} is no floor)"
        return Window(figure, max(spread_ms, late_ms, floor_ms) / 1000,
                      f"largest of {FACTOR:g} x measured {what} p99 {p99_ms:.2f} ms = {spread_ms:.2f} ms, host "
                      f"lateness {late_ms:.2f} ms{floor}")

    def _measured(self, figure: str) -> tuple[str, float] | None:
        """What was measured of the kind ``figure`` bounds, and its p99 (ms); None where too little."""
        if figure == "sdo_response_max_ms" and self.sdo is not None:
            return "SDO", self.sdo.p99_ms
        observed = self._observed.get(figure, [])
        if len(observed) < MIN_OBSERVED:
            return None
        return f"{figure.split('_')[0].upper()} ({len(observed)} answers in the run)", percentile(observed, 0.99)
