"""The run as a bench sees it: custody of the device, one reason when it is gone, exit codes, Ctrl-C.

pre-flight and snapshot (the dut fixture) -> tests -> give the device back (end of the run, or at
once on Ctrl-C/SIGTERM, or after the bus or device is lost) -> report. The exit status follows
exit_codes.RunExit, and tells the three outcomes apart (shared DESIGN §8):

- FAIL (NON_CONFORMANT): the device broke a rule; also when it stopped answering in a test (that test fails,
  naming the last frames sent, the rest are not run) or its start-up replies broke CiA 301;
- COULD NOT TEST: nothing about the device was shown: it never answered, the bus, adapter or bench failed, or
  the operator stopped the run;
- INTERNAL ERROR: our code raised what is no finding about the device (``outcomes``); exit 3 only when nothing
  else failed, and never counted in a verdict.
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass, field

import pytest

from encoder_conformance.coverage import Kind
from encoder_conformance.dut.custody.custody import Custody, RestoreRecord
from encoder_conformance.exit_codes import DESCRIPTIONS, RunExit
from encoder_conformance.plugin.interrupt import InterruptGuard
from encoder_conformance.plugin.outcomes import is_internal_error
from encoder_conformance.plugin.reporting import report_dir, runs_suites
from encoder_conformance.plugin.skips import booked


@dataclass(frozen=True)
class StopVerdict:
    """Why the run stopped on a finding about the device: the check, its area, the clause, what was seen."""

    check: str  # a test id, or "start-up check"
    area: str
    source: str  # the clause or manual section (document, version, section)
    message: str
    recorded: bool = False  # the check is a test whose own report already holds the failure

    def line(self) -> str:
        """One line: the check, the first thing seen, the clause."""
        seen = " ".join(line.strip() for line in self.message.splitlines()[:2])
        return f"{self.check} failed: {seen} ({self.source})"


@dataclass
class RunState:
    """What the lifecycle knows about this run."""

    guard: InterruptGuard
    custody: Custody | None = None
    stopped: str | None = None  # could not test: why
    rejected: str | None = None  # the start-up check found another product (acceptance: an identity failure)
    failed: StopVerdict | None = None  # the device failed so that the run could not go on (a FAIL, not 69)
    lost_in: str | None = None  # the test during which the device stopped answering
    collected: int = 0
    reported: set[str] = field(default_factory=set)  # test ids with a call-phase report
    failed_tests: set[str] = field(default_factory=set)  # test ids with a failure about the device (any phase)
    internal_errors: set[str] = field(default_factory=set)  # test ids with an internal error of the tool
    not_testable: dict[str, str] = field(default_factory=dict)  # test id -> the hold that kept it from judging

    @property
    def record(self) -> RestoreRecord | None:
        return None if self.custody is None else self.custody.record


STATE = pytest.StashKey[RunState]()


def state_of(config: pytest.Config) -> RunState | None:
    return config.stash.get(STATE, None)


def start(config: pytest.Config) -> None:
    """Install the Ctrl-C/SIGTERM handling for a conformance run."""
    if not runs_suites(config):
        return
    state = RunState(InterruptGuard(on_stop=lambda reason: _stop_device(config, reason)))
    config.stash[STATE] = state
    _RUN[0] = config
    state.guard.install()


def _stop_device(config: pytest.Config, reason: str) -> None:
    state = state_of(config)
    if state is not None and state.custody is not None:
        state.custody.dut.stop(reason)


def adopt(config: pytest.Config, custody: Custody) -> None:
    """The dut fixture took the device into custody: give it back when the run ends, however it ends."""
    state = state_of(config)
    if state is not None:
        state.custody = custody
        if state.guard.signum is not None:
            custody.dut.stop(state.guard.reason)


def custody_of(config: pytest.Config) -> Custody | None:
    state = state_of(config)
    return None if state is None else state.custody


def normal_budget_s(custody: Custody) -> float:
    """Time the restore may take at the end of a run: resets, stores and reboots the profile allows, and reads."""
    timing = custody.dut.profile.timing
    entries = len(custody.snapshot.entries) if custody.snapshot else 0
    return 10.0 + 3 * timing.bootup_max_ms / 1000 + 2 * timing.store_max_ms / 1000 + 0.05 * entries


def give_back(config: pytest.Config) -> RestoreRecord | None:
    """Restore the device as found (once); within the interrupt budget after Ctrl-C."""
    state = state_of(config)
    if state is None or state.custody is None:
        return None
    custody = state.custody
    if custody.record is None:
        interrupted = state.guard.signum is not None
        seconds = state.guard.remaining() if interrupted else normal_budget_s(custody)
        state.guard.trace(f"restore starts ({seconds:.2f} s)")
        with state.guard.shield():
            record = custody.give_back(seconds)
        state.guard.trace("restore done")
        folder = report_dir(config)
        if folder is not None:
            record.save(folder / "device-restore.json")
    return custody.record


_RUN: list[pytest.Config | None] = [None]  # the running config, for pytest_keyboard_interrupt (gets none)


def give_back_now(excinfo: pytest.ExceptionInfo[BaseException]) -> None:
    """Interrupted or stopped: restore at once, before pytest spends time formatting the traceback."""
    config = _RUN[0]
    if config is not None:
        trace(config, "keyboard interrupt hook")
        give_back(config)
    traceback = getattr(excinfo, "traceback", None)
    if traceback and type(getattr(excinfo, "value", None)) is KeyboardInterrupt:
        # pytest shows only the last entry of a Ctrl-C; a repr of the whole deep stack takes ~0.5 s
        excinfo.traceback = traceback[-1:]


def trace(config: pytest.Config, phase: str) -> None:
    state = state_of(config)
    if state is not None:
        state.guard.trace(phase)


def device_gone(config: pytest.Config) -> str | None:
    """Why the run cannot go on (bus lost, bench failed, device silent), or None."""
    state = state_of(config)
    if state is None or state.custody is None:
        return None
    return state.custody.dut.lost


LOST_PROPERTY = "device_lost"
LOST_CLAUSE = ("CiA 301 v4.2.0 §7.2.4.3 (SDO: every request is answered) and §7.2.8.3.2.2 (the heartbeat is sent "
               "every producer heartbeat time)")


def lost_text(config: pytest.Config) -> str:
    """The device stopped answering: why, and the last frames the tester sent before it went silent."""
    custody = custody_of(config)
    if custody is None or not custody.dut.device_lost:
        return ""
    return f"the device stopped answering: {custody.dut.lost}\nthe last frames sent before:\n{custody.dut.lost_frames}"


def note_loss(item: pytest.Item, report: pytest.TestReport) -> None:
    """The device stopped answering in this test: its report says so, naming the last frames sent; a test that
    did not fail by itself (the loss showed in its clean-up) fails at its teardown."""
    state = state_of(item.config)
    text = lost_text(item.config)
    if state is None or not text or state.lost_in not in (None, item.nodeid):
        return
    state.lost_in = item.nodeid
    if report.when == "teardown" and not report.failed and item.nodeid not in state.failed_tests:
        report.outcome, report.longrepr = "failed", text
    if report.failed and (LOST_PROPERTY, text) not in item.user_properties:
        report.sections.append(("the device stopped answering", text))
        report.user_properties.append((LOST_PROPERTY, text))  # the run summary's message names the frames
        item.user_properties.append((LOST_PROPERTY, text))


def stop_run(config: pytest.Config, reason: str) -> None:
    """The run cannot start or go on (pre-flight failed, bus gone): one reason, exit code COULD_NOT_TEST.

    Raised with pytest's own 'interrupted' code, which keeps pytest's summaries; final_exit_status
    turns it into COULD_NOT_TEST.
    """
    state = state_of(config)
    if state is not None:
        state.stopped = state.stopped or reason
        pytest.exit(f"could not test: {reason}", returncode=pytest.ExitCode.INTERRUPTED)
    pytest.exit(f"could not test: {reason}", returncode=RunExit.COULD_NOT_TEST)


def reject_device(config: pytest.Config, reason: str) -> None:
    """The device answers but is not the product bought (acceptance): a verdict, not 'could not test'; the
    run ends with one reason and exit code NON_CONFORMANT, the summary records an identity failure."""
    state = state_of(config)
    if state is not None:
        state.rejected = reason
    pytest.exit(f"FAIL identity: {reason}", returncode=RunExit.NON_CONFORMANT)


def fail_run(config: pytest.Config, verdict: StopVerdict) -> None:
    """The device failed so that the run cannot go on (start-up replies that break CiA 301, a device that stopped
    answering in a test): exit code NON_CONFORMANT, the tests not run counted as not run."""
    state = state_of(config)
    if state is not None:
        state.failed = state.failed or verdict
    pytest.exit(f"FAIL {verdict.line()}", returncode=RunExit.NON_CONFORMANT)


def stop_if_gone(config: pytest.Config) -> None:
    """Before and after each test: a device that stopped answering ends the run as a FAIL (the test it stopped in
    failed); a lost bus or a failed bench ends it with one reason (could not test)."""
    reason = device_gone(config)
    if not reason:
        return
    state = state_of(config)
    custody = custody_of(config)
    if state is not None and custody is not None and custody.dut.device_lost:
        fail_run(config, StopVerdict(state.lost_in or "between two tests", "", LOST_CLAUSE,
                                     f"the device stopped answering: {reason}", recorded=state.lost_in is not None))
    stop_run(config, reason)


def note_report(config: pytest.Config, report: pytest.TestReport) -> None:
    state = state_of(config)
    if state is None:
        return
    if report.when == "call" or report.outcome != "passed":
        state.reported.add(report.nodeid)
    if report.failed:
        (state.internal_errors if is_internal_error(report) else state.failed_tests).add(report.nodeid)
    elif report.skipped:
        kind, hold = booked(report)
        if kind is Kind.NOT_TESTABLE:
            state.not_testable[report.nodeid] = hold.meaning if hold else Kind.NOT_TESTABLE.value


def final_exit_status(session: pytest.Session) -> None:
    """Interrupted > could not test > a FAIL that stopped the run > device not restored > a device failure >
    an internal error of the tool (3, only where nothing else failed) > incomplete (6: a check in scope was not
    testable) > pytest's own verdict."""
    state = state_of(session.config)
    if state is None:
        return
    state.guard.trace("session finished")
    state.guard.uninstall()
    _RUN[0] = None
    record = state.record
    if state.guard.exit_code is not None:
        session.exitstatus = state.guard.exit_code
    elif state.stopped or session.exitstatus == RunExit.COULD_NOT_TEST:
        session.exitstatus = RunExit.COULD_NOT_TEST
    elif state.rejected or state.failed:
        session.exitstatus = RunExit.NON_CONFORMANT
    elif record is not None and not record.ok:
        session.exitstatus = RunExit.NOT_RESTORED
    elif state.failed_tests:
        session.exitstatus = RunExit.NON_CONFORMANT
    elif state.internal_errors and session.exitstatus == pytest.ExitCode.TESTS_FAILED:
        session.exitstatus = RunExit.INTERNAL_ERROR
    elif state.not_testable and session.exitstatus == pytest.ExitCode.OK:
        session.exitstatus = RunExit.INCOMPLETE
    _write_outcome(session, state)


OUTCOME_FILE = "run-outcome.json"


def _write_outcome(session: pytest.Session, state: RunState) -> None:
    """The run's verdict for machines: exit code and its meaning, why it stopped, whether the device is restored."""
    folder = report_dir(session.config)
    if folder is None:
        return
    code = int(session.exitstatus)
    record = state.record
    outcome = {
        "exit_code": code,
        "meaning": next((text for known, text in DESCRIPTIONS.items() if known == code), "interrupted"),
        "stopped": state.stopped or (state.failed.line() if state.failed else None),
        "device_failed": state.failed.line() if state.failed else None,
        "internal_errors": sorted(state.internal_errors),
        "interrupted": state.guard.reason if state.guard.signum is not None else None,
        "tests_collected": state.collected,
        "tests_reported": len(state.reported),
        "device_restored": None if record is None else record.ok,
        # the run's own clock from the interrupt to here (device given back, verdict decided); what a
        # caller measures adds the process's exit and its own wake-up on a loaded machine
        "stopped_after_s": state.guard.since_interrupt(),
    }
    (folder / OUTCOME_FILE).write_text(json.dumps(outcome, indent=1), encoding="utf-8")


def ended_early(config: pytest.Config) -> bool:
    """Interrupted or stopped: 'every test skipped' means nothing then."""
    state = state_of(config)
    return state is not None and (state.guard.signum is not None or state.stopped is not None
                                  or state.rejected is not None or state.failed is not None)


def note_collected(session: pytest.Session) -> None:
    state = state_of(session.config)
    if state is not None:
        state.collected = len(session.items)


def summary_lines(config: pytest.Config) -> list[tuple[str, bool]]:
    """(text, alarm) lines for the terminal and the HTML summary."""
    state = state_of(config)
    if state is None:
        return []
    lines: list[tuple[str, bool]] = []
    not_run = max(0, state.collected - len(state.reported))
    if state.guard.signum is not None:
        lines.append((f"{state.guard.reason}: {not_run} test(s) not run", True))
    elif state.stopped:
        lines.append((f"could not test: {state.stopped}; {not_run} test(s) not run", True))
    elif state.rejected:
        lines.append((f"FAIL identity: {state.rejected}; {not_run} test(s) not run", True))
    elif state.failed:
        lines.append((f"FAIL {state.failed.line()}; {not_run} test(s) not run", True))
    if state.internal_errors:
        lines.append((f"{len(state.internal_errors)} internal error(s) of the tool: please report them (not counted "
                      "in any verdict): " + ", ".join(sorted(state.internal_errors)[:5]), True))
    if state.not_testable:
        why = Counter(state.not_testable.values()).most_common()
        lines.append((f"INCOMPLETE: {len(state.not_testable)} check(s) in scope were not testable, so no PASS ("
                      + "; ".join(f"{count} x {meaning}" for meaning, count in why) + ")", True))
    record = state.record
    if record is None:
        return lines
    if state.custody and state.custody.snapshot_path:
        lines.append((f"device snapshot: {state.custody.snapshot_path}", False))
    wear = sum(record.run_store_commands.values())
    detail = ", ".join(f"{count} x {kind}" for kind, count in sorted(record.run_store_commands.items()))
    lines.append((f"store/restore commands (EEPROM wear): {wear} by the tests{f' ({detail})' if detail else ''}, "
                  f"{record.restore_store_commands} by the restore", False))
    if record.done:
        lines.append((f"left changed by the run: {len(record.left_changed)} value(s) in use, "
                      f"{len(record.stored_changed)} stored value(s); restore wrote {len(record.written)} value(s) "
                      f"and stored with {', '.join(record.store_commands) or 'nothing'} in {record.seconds:.2f} s",
                      False))
    shown = 12
    sections = (("left changed in use", record.left_changed), ("stored value changed", record.stored_changed))
    for title, changes in sections:
        lines += [(f"  {title}: {change.describe()}", False) for change in changes[:shown]]
        if len(changes) > shown:
            lines.append((f"  ... and {len(changes) - shown} more (device-restore.json)", False))
    if record.memory:
        lines.append((f"MEMORY NOT AS FOUND: {record.memory}", True))
    if record.ok and record.memory:
        lines.append(("every value given back and checked, but the device is not as found: its memory (above)", True))
    elif record.ok:
        lines.append(("device restored as found: every value checked", False))
    else:
        for failure in record.failures:
            lines.append((f"NOT RESTORED: {failure}", True))
        snapshot = state.custody.snapshot_path if state.custody else None
        if snapshot:
            lines.append((f"put the device back with: encoder-conformance restore --from {snapshot} "
                          "(and the same --can-*/--node-id options)", True))
    return lines
