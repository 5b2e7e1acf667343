"""Is the device still itself while it is fuzzed: NMT state, heartbeat, no EMCY (CiA 301 §7.2.7, §7.2.8.3.2).

Cheap per example: it only looks at the frames that came since it last looked (a heartbeat reporting
another state or a boot-up; an EMCY, only a warning: ``EMCY_RULE``); it never waits. Over the whole test
it checks that the heartbeat kept coming: no gap over ``gap_limit_s`` (a device that stalled or
restarted), and one more heartbeat after the last example.
"""

from __future__ import annotations

import itertools

import can

from encoder_conformance.cia.cia301 import NmtState
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link.frames import Mark, format_frames
from encoder_conformance.dut.link.windows import UNMEASURED_MARGIN_S

#: heartbeat periods without a heartbeat that count as a stalled producer, and at least GAP_FLOOR_S (not a
#: timing verdict: those are test_heartbeat's, with the tester's own lateness; this one survives a busy tester)
GAP_PERIODS = 4
GAP_FLOOR_S = 0.5
#: why an EMCY while fuzzed is only a warning: CiA 301 §7.2.7.1 triggers EMCY on device-internal errors and
#: lists no SDO protocol error among its codes, but forbids no EMCY either
EMCY_RULE = ("no EMCY for refused SDO requests: CiA 301 §7.2.7.1 triggers EMCY on device-internal errors, a "
             "refused request is none (our reading: the text forbids no EMCY here)")


class DeviceWatch:
    """Watches the heartbeat state and EMCY frames of one node while a fuzz test runs."""

    def __init__(self, dut: DeviceUnderTest, heartbeat_ms: int, emcy_cob_id: int | None) -> None:
        self.dut = dut
        self.period_s = heartbeat_ms / 1000
        self.emcy_cob_id = emcy_cob_id
        self.state: int | None = None
        self.start: Mark = dut.frames.mark()
        self._cursor: Mark = self.start  # frames up to here were looked at
        self.emcy: list[can.Message] = []  # EMCY frames seen while fuzzed

    def begin(self) -> str | None:
        """Note the NMT state from the next heartbeat; a problem if none comes while 1017h says it should."""
        self.start = self._cursor = self.dut.frames.mark()
        if not self.period_s:
            return None
        beat = self.dut.wait_heartbeat(self.start, self.gap_limit_s)
        if beat is None:
            return f"no heartbeat within {self.gap_limit_s * 1000:.0f} ms (1017h: {self.period_s * 1000:.0f} ms)"
        self.state = beat.data[0]
        return None

    @property
    def gap_limit_s(self) -> float:
        return max(GAP_PERIODS * self.period_s, GAP_FLOOR_S) + UNMEASURED_MARGIN_S

    def _emcy(self, msg: can.Message) -> bool:
        return msg.is_rx and msg.arbitration_id == self.emcy_cob_id and not msg.is_remote_frame

    def problems(self) -> list[str]:
        """What the frames since the last look show (also those between examples): a boot-up, another NMT
        state. EMCY frames are kept in ``emcy`` (a warning, see ``EMCY_RULE``)."""
        found = []
        since, self._cursor = self._cursor, self.dut.frames.mark()
        for msg in self.dut.frames.since(since, lambda m: self.dut.is_heartbeat(m) or self._emcy(m)):
            if self._emcy(msg):
                self.emcy.append(msg)
            elif msg.data and msg.data[0] == NmtState.BOOT_UP:
                found.append("boot-up message: the device restarted")
            elif self.state is not None and msg.data and msg.data[0] != self.state:
                found.append(f"heartbeat reports NMT state {msg.data[0]:02X}h, {self.state:02X}h before the requests")
        return found

    def finish(self) -> list[str]:
        """The heartbeat kept coming over the whole test, and comes once more now."""
        if not self.period_s:
            return []
        limit = self.gap_limit_s
        end = self.dut.frames.mark()
        if self.dut.wait_heartbeat(end, limit) is None:
            return [f"the heartbeat stopped: none within {limit * 1000:.0f} ms after the last example"]
        beats = [m for m in self.dut.frames.since(self.start, self.dut.is_heartbeat) if m.data]
        gaps = [(b.timestamp - a.timestamp, a, b) for a, b in itertools.pairwise(beats)]
        late = [(gap, a, b) for gap, a, b in gaps if gap > limit]
        if not late:
            return []
        gap, a, b = max(late, key=lambda item: item[0])
        return [f"{len(late)} heartbeat gap(s) over {limit * 1000:.0f} ms while fuzzed, the longest "
                f"{gap * 1000:.0f} ms:\n{format_frames([a, b])}"]
