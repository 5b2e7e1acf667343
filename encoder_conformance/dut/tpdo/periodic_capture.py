"""One capture for the periodic streams: heartbeat and TPDO event timer measured at the same time.

Each period test needs >= 50 intervals (2.5 s at 50 ms); measured one after the other they were
the two longest tests of every run. Here both streams are set up together, captured once, and each
test judges its own stream (``plugin/suite_helpers/periodic.py``). The streams stay independent: a TPDO that cannot be
configured does not touch the heartbeat verdict, and the other way round. The capture owns its preconditions: no
error active before it starts (an earlier test's, e.g. an EMCY trigger's: NMT reset communication clears it, noted
in both streams), and operational seen in the heartbeat's state byte before the TPDO stream is counted (a device
that holds an error stays in pre-operational: the TPDO stream then fails naming the state, not "0 TPDOs").
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import NmtState
from encoder_conformance.coverage import Hold
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.link.latency_probe import HostLatency, LatencyProbe, TwinLateness
from encoder_conformance.dut.nmt.commands import send_command
from encoder_conformance.dut.nmt.heartbeat_state import state_window_s
from encoder_conformance.dut.nmt.nmt_preconditions import error_register
from encoder_conformance.dut.nmt.nmt_states import return_to_preoperational
from encoder_conformance.dut.nmt.persistent_error import describe_hold, persisting_error
from encoder_conformance.dut.tpdo.tpdo_choice import NoUsableTpdo, choose_tpdo
from encoder_conformance.dut.tpdo.tpdo_under_test import TpdoUnderTest

EVENT_TIMER_TYPES = [255, 254]  # event-driven types whose event timer sub 5 sets a period
HEARTBEAT = 0x1017  # producer heartbeat time (ms)


@dataclass
class PeriodicStream:
    """One stream's frames, or why it could not be captured (a skip reason or a failure text)."""

    what: str
    period_ms: int
    wanted: int
    timestamps: list[float] = field(default_factory=list)
    cob_id: int | None = None
    skip: str | None = None
    skip_hold: Hold | None = None  # in scope: why the stream could not be captured
    error: str | None = None
    notes: list[str] = field(default_factory=list)
    deviations: list[tuple[str, str]] = field(default_factory=list)


@dataclass
class PeriodicCapture:
    """The heartbeat and event-timer streams, captured in the same window in operational."""

    heartbeat: PeriodicStream
    event_timer: PeriodicStream
    captured_in: str = ""  # node id of the test whose bus trace holds the frames
    host: HostLatency | None = None  # how late the tester's host ran during the capture
    started: bool = False  # the node was started (NMT operational) for the TPDO stream
    clock: str = ""  # which clock stamped the frames (FrameLog.clock)
    kept_error: int = 0  # 1001h after the reset communication that was to clear an error left before the capture
    #: entries the capture must not write (an acceptance: those that may alias another, ``aliased_values``)
    leave_alone: frozenset[tuple[int, int]] = frozenset()

    @classmethod
    def at_test_period(cls, dut: DeviceLink, count: int) -> PeriodicCapture:
        """Both streams at the profile's heartbeat test period, ``count`` frames each."""
        period = dut.profile.timing.heartbeat_test_period_ms
        return cls(PeriodicStream("heartbeat", period, count), PeriodicStream("event timer", period, count),
                   clock=dut.frames.clock.describe())

    def take(self, dut: DeviceLink, twin: TwinLateness | None) -> None:
        """Set up both streams, capture them, and put the settings back and the device into pre-operational
        (a problem with that fails the stream(s) it concerns)."""
        journal = SettingsJournal(dut)
        try:
            self._capture(dut, journal, twin)
        finally:
            self._put_back(dut, journal)

    def _put_back(self, dut: DeviceLink, journal: SettingsJournal) -> None:
        """Pre-operational again and the settings as found; a problem fails the stream(s) it concerns."""
        if not dut.usable:
            return
        if self.started:
            try:
                return_to_preoperational(dut)
            except AssertionError as exc:
                self.event_timer.error = self.event_timer.error or str(exc)  # the TPDO stream started the node
        problems = journal.restore() if dut.usable else []
        if problems:
            self.heartbeat.error = self.event_timer.error = "could not put back: " + "; ".join(problems)

    def _capture(self, dut: DeviceLink, journal: SettingsJournal, twin: TwinLateness | None) -> None:
        beat, timer = self.heartbeat, self.event_timer
        self._no_error_left(dut)
        if dut.profile.capabilities.heartbeat_producer:
            _configure(beat, lambda: journal.write(HEARTBEAT, 0, beat.period_ms.to_bytes(2, "little")))
        else:
            beat.skip = "not applicable: the profile declares no heartbeat producer (capabilities.heartbeat_producer)"
        if dut.profile.capabilities.tpdos:
            _configure(timer, lambda: _configure_event_timer(dut, journal, timer, self.leave_alone))
        else:
            timer.skip = "not applicable: the profile declares no TPDOs (capabilities.tpdos)"
        streams = [s for s in (beat, timer) if not (s.skip or s.error)]
        if not streams:
            return
        if timer in streams:
            self.started = True
            started = send_command(dut, "start")
            problem = _not_operational(dut, started, beat) if beat in streams else None
            if problem is not None and self.kept_error:  # an error no reset clears may hold it in pre-operational
                timer.skip = describe_hold(dut, "the event-timer TPDO stream", self.kept_error)
                timer.skip_hold = Hold.PERSISTENT_ERROR
                streams.remove(timer)
            elif problem is not None:
                timer.error = problem
                streams.remove(timer)
        mark = dut.frames.mark()
        # both streams run at once: one window for the two (a silent device costs it once, not twice)
        deadline = Deadline(beat.wanted * beat.period_ms * 1.5 / 1000 + 0.5)
        with LatencyProbe(twin) as probe:
            if beat in streams:
                hits = dut.frames.wait_count(lambda m: dut.is_heartbeat(m) and bool(m.data), beat.wanted,
                                             deadline.remaining(), mark)
                beat.timestamps = [m.timestamp for m in hits]
            if timer in streams:
                hits = dut.frames.wait_count(lambda m: m.is_rx and m.arbitration_id == timer.cob_id, timer.wanted,
                                             deadline.remaining(), mark)
                timer.timestamps = [m.timestamp for m in hits]
        self.host = probe.result()

    def _no_error_left(self, dut: DeviceLink) -> None:
        """1001h = 0 before the capture; an error left active by an earlier test is cleared by NMT reset
        communication (its boot-up waited for), and both streams say so. An error the reset does not clear is
        kept (``kept_error``): where it holds the device out of operational, the TPDO stream is not testable."""
        found = error_register(dut)
        if not found:
            return
        self.kept_error = persisting_error(dut) or 0  # NMT reset communication, unless it survived one already
        note = (f"1001h = {found:02X}h before the capture: "
                + (f"the device keeps it after NMT reset communication (1001h = {self.kept_error:02X}h)"
                   if self.kept_error else "NMT reset communication sent to clear it"))
        self.heartbeat.notes.append(note)
        self.event_timer.notes.append(note)


def _not_operational(dut: DeviceLink, started: Mark, beat: PeriodicStream) -> str | None:
    """None once the heartbeat reports operational after NMT start (settle time + 2 periods), else what it shows."""
    wait = state_window_s(dut, beat.period_ms)
    if dut.wait_heartbeat(started, wait, state=NmtState.OPERATIONAL) is not None:
        return None
    seen = [f"{m.data[0]:02X}h" for m in dut.frames.since(started, dut.is_heartbeat) if m.data][-4:]
    return (f"event timer: NMT start, but no heartbeat with 05h (operational) within {wait * 1000:.0f} ms: the "
            f"heartbeat reports {', '.join(seen) or 'nothing'}, 1001h = {error_register(dut):02X}h; the TPDO stream "
            "was not counted")


def _configure(stream: PeriodicStream, configure: Callable[[], None]) -> None:
    """Run one stream's set-up; an abort or refusal becomes that stream's failure, not the other's."""
    try:
        configure()
    except NoUsableTpdo as exc:
        stream.deviations.extend(exc.deviations)
        stream.skip, stream.skip_hold = str(exc), exc.hold
    except (SdoAbortedError, AssertionError) as exc:
        stream.error = f"{stream.what}: setting up the capture failed: {exc}"


def _configure_event_timer(dut: DeviceLink, journal: SettingsJournal, stream: PeriodicStream,
                           leave_alone: frozenset[tuple[int, int]]) -> None:
    choice = choose_tpdo(dut, 5, EVENT_TIMER_TYPES, leave_alone)
    stream.deviations.extend(choice.deviations)
    tpdo = TpdoUnderTest.chosen(dut, journal, choice)
    stream.notes.extend(choice.notes)
    stream.cob_id = tpdo.can_id()
    tpdo.configure(trans_type=tpdo.trans_type, event_timer=stream.period_ms)
