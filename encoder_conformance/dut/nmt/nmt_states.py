"""The one way tests and fixtures bring the device into an NMT state, and check it got there by what that state
answers: the heartbeat's state byte (CiA 301 v4.2.0 §7.2.8.3.2.2: 7Fh pre-operational, 05h operational, 04h
stopped), never an SDO request in stopped (§7.3.2.2 offers none there). A state not reached fails naming the state
the heartbeat reports, before any other check could trip over it.

- ``reach``: pre-operational, operational or stopped, the heartbeat switched on at the profile's state-watch period
  where it is off (put back by the journal), and its state byte seen. Without a heartbeat producer the state itself
  cannot be seen: an SDO answer shows pre-operational or operational, its absence stopped (noted).
- ``start_operational``: ``reach`` operational; operational not reached while the device keeps an error that reset
  communication does not clear is not testable (``persistent_error``).
- ``return_to_preoperational``: the put-back after a test (no journal): NMT enter pre-operational, and the heartbeat's
  7Fh where the caller knows its period, else SDO answering again.

The state after a reset is no transition here: the suites that reset either judge the reset itself (its boot-up and
the state it settles in: ``boot_state``, test_nmt's ``test_state_after_reset``, the state machine's reset rule) or
need only the boot-up (``dut.nmt.reset_node``).
"""

from __future__ import annotations

from encoder_conformance.cia.cia301 import NmtState
from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark, format_frames
from encoder_conformance.dut.link.notes import Notes
from encoder_conformance.dut.nmt.commands import reset_node_and_wait, send_command
from encoder_conformance.dut.nmt.heartbeat_state import describe, is_state_beat, leave_stopped, wait_state
from encoder_conformance.dut.nmt.heartbeat_state import state_window_s as window_s
from encoder_conformance.dut.nmt.persistent_error import error_register, raise_if_held_by_error

HEARTBEAT = 0x1017  # producer heartbeat time (ms)
#: the suites' names for the states, their heartbeat byte and the NMT command that enters each
STATES = {"pre-operational": (NmtState.PRE_OPERATIONAL, "pre-operational"),
          "operational": (NmtState.OPERATIONAL, "start"), "stopped": (NmtState.STOPPED, "stop")}
CLAUSE = "CiA 301 v4.2.0 §7.3.2.2 (NMT state diagram), §7.2.8.3.2.2 (heartbeat state byte)"


def confirm(dut: DeviceLink, after: Mark, state: int, period_ms: float, why: str) -> None:
    """A heartbeat after ``after`` reports ``state``; else AssertionError naming the state it reports (operational
    not reached: not testable where an error the device keeps explains it)."""
    wait = window_s(dut, period_ms)
    observed = wait_state(dut, after, state, wait)
    if observed == state:
        return
    beats = dut.frames.since(after, lambda m: is_state_beat(dut, m))
    problem = (f"{why}: the heartbeat reports {describe(observed)}, not {describe(state)}, within {wait * 1000:.0f} "
               f"ms (1017h = {period_ms:.0f} ms) ({CLAUSE})\n{format_frames(beats[-4:]) or '  no heartbeat'}")
    if state == NmtState.OPERATIONAL:
        raise_if_held_by_error(dut, why)  # an error the device keeps may hold it in pre-operational
    raise AssertionError(problem)


def heartbeat_on(dut: DeviceLink, journal: SettingsJournal) -> int:
    """1017h now, set to the profile's state-watch period (put back by the journal) where it is 0. Needs SDO: the
    device is brought out of stopped first (``leave_stopped``, else NMT reset communication and its boot-up)."""
    if not leave_stopped(dut):
        mark = send_command(dut, "reset-communication")
        assert dut.wait_bootup(mark) is not None, (
            f"no boot-up within {dut.profile.timing.bootup_max_ms:.0f} ms after reset communication (sent to bring "
            f"the device out of stopped)\n{format_frames(dut.frames.since(mark)[-8:])}")
    period = dut.read_uint(HEARTBEAT)
    if not period:
        period = dut.profile.timing.heartbeat_state_period_ms
        journal.write(HEARTBEAT, 0, period.to_bytes(2, "little"))
    return period


def reach(dut: DeviceLink, journal: SettingsJournal, notes: Notes, state_name: str) -> None:
    """Bring the device into ``state_name`` (pre-operational, operational, stopped) and see it there (see the
    module's docstring); AssertionError naming the state observed otherwise."""
    state, command = STATES[state_name]
    if not dut.profile.capabilities.heartbeat_producer:
        _reach_by_services(dut, notes, state_name)
        return
    period = heartbeat_on(dut, journal)
    mark = send_command(dut, command)
    confirm(dut, mark, state, period, f"NMT {command} (to enter {state_name})")


def _reach_by_services(dut: DeviceLink, notes: Notes, state_name: str) -> None:
    """Without a heartbeat: SDO answers in pre-operational and operational, none in stopped."""
    state, command = STATES[state_name]
    send_command(dut, command)
    if state == NmtState.STOPPED:
        answered = dut.responds(dut.sdo_silence_s)
        assert not answered, f"NMT stop: SDO still answered (no heartbeat producer to show the state) ({CLAUSE})"
    else:
        answered = dut.responds() or dut.responds()  # a second request covers the device's settle time
        assert answered, f"NMT {command}: no SDO answer after it, as in stopped (no heartbeat producer) ({CLAUSE})"
    notes.note(f"NMT {command}: SDO {'not ' if state == NmtState.STOPPED else ''}answered (no heartbeat producer: "
               f"{state_name} itself is not seen)")


def start_operational(dut: DeviceLink, journal: SettingsJournal, notes: Notes) -> None:
    """NMT start, and operational seen in the heartbeat (or an SDO answer without one); AssertionError otherwise,
    naming the state the heartbeat reports and 1001h. Works from stopped too."""
    try:
        reach(dut, journal, notes, "operational")
    except AssertionError as exc:
        register = f", 1001h = {error_register(dut):02X}h" if dut.usable and leave_stopped(dut) else ""
        raise AssertionError(f"{exc}{register}") from None


def return_to_preoperational(dut: DeviceLink, period_ms: int | None = None) -> None:
    """NMT enter pre-operational: the heartbeat's 7Fh where ``period_ms`` (1017h) is known, else SDO answering
    again; marks the device lost when it went silent, and recovers with reset node (raising AssertionError) when it
    is alive but not back."""
    mark = send_command(dut, "pre-operational")
    if period_ms:
        observed = wait_state(dut, mark, NmtState.PRE_OPERATIONAL, window_s(dut, period_ms))
        if observed == NmtState.PRE_OPERATIONAL:
            return
        seen = f"the heartbeat reports {describe(observed)}"
    elif dut.responds() or dut.responds():  # a second request covers the device's settle time
        return
    else:
        seen = "no SDO answer"
    if not dut.heard_since(mark):
        dut.mark_lost("no SDO answer and no frame after NMT enter pre-operational")
        return
    reset_node_and_wait(dut)  # alive but not back in pre-operational: recover, and say so
    raise AssertionError(f"the device did not return to pre-operational on NMT enter pre-operational ({seen}, but "
                         f"it still sends frames); recovered with NMT reset node ({CLAUSE})")
