"""The NMT state as the heartbeat reports it, read from the frames and never by SDO: CiA 301 v4.2.0 §7.2.8.3.2.2
(the state byte: 04h stopped, 05h operational, 7Fh pre-operational), §7.3.2.2 (stopped offers no SDO, only NMT and
error control). What the suites and the persistent-error check ask before their first SDO request."""

from __future__ import annotations

import can

from encoder_conformance.cia.cia301 import NMT_COB_ID, STATE_NAMES, NmtCommand, NmtState
from encoder_conformance.dut.link.device import DeviceLink, answer_window
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.nmt.commands import send_command

#: the states that offer SDO (CiA 301 v4.2.0 §7.3.2.2)
SDO_STATES = frozenset({NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL})
#: frames of the log looked back over for the newest NMT command and heartbeat (a few seconds at a 10 ms heartbeat)
LOOK_BACK = 2000


def state_change_s(dut: DeviceLink, period_ms: float) -> float:
    """How long a state change may take to show in the heartbeat: the settle time plus two heartbeat periods."""
    return (dut.profile.timing.nmt_settle_ms + 2 * period_ms) / 1000


def state_window_s(dut: DeviceLink, period_ms: float) -> float:
    """How long the heartbeat reporting a state change is waited for: a frame the device owes within
    ``state_change_s``, so its answer window (the wait ends when it comes). Under a busy process a tester saw no
    heartbeat at all for 120 ms at 1017h = 10 ms, a false failure of the transition."""
    return answer_window(state_change_s(dut, period_ms))


def describe(state: int | None) -> str:
    """'7Fh (pre-operational)', or 'no heartbeat'."""
    return "no heartbeat" if state is None else f"{state:02X}h ({STATE_NAMES.get(state, 'no NMT state')})"


def is_state_beat(dut: DeviceLink, msg: can.Message) -> bool:
    """A heartbeat of the node that carries a state (not its boot-up message, 00h)."""
    return dut.is_heartbeat(msg) and bool(msg.data) and msg.data[0] != 0


def _is_command(dut: DeviceLink, msg: can.Message) -> bool:
    """An NMT command this tester sent to the node or to all nodes."""
    return (not msg.is_rx and msg.arbitration_id == NMT_COB_ID and len(msg.data) == 2
            and msg.data[1] in (0, dut.node_id))


def newest_state(dut: DeviceLink, after: Mark) -> int | None:
    """The state the newest heartbeat after ``after`` reports (None: none came)."""
    beats = dut.frames.since(after, lambda m: is_state_beat(dut, m))
    return beats[-1].data[0] if beats else None


def wait_state(dut: DeviceLink, after: Mark, state: int, window_s: float) -> int | None:
    """The heartbeat after ``after`` that reports ``state`` (waited for up to ``window_s``), else the state the
    newest one reports (None: no heartbeat at all)."""
    if dut.wait_heartbeat(after, window_s, state=state) is not None:
        return state
    return newest_state(dut, after)


def settle(dut: DeviceLink, after: Mark, state: int) -> bool:
    """After an NMT command at ``after``: until a heartbeat reports ``state``, at most the profile's settle time
    (``nmt_settle_ms``); True once one did. Without a heartbeat producer nothing on the bus shows the state: the
    settle time is waited out (False). A heartbeat slower than the settle time ends the wait at it, as before."""
    settle_s = dut.profile.timing.nmt_settle_ms / 1000
    if dut.profile.capabilities.heartbeat_producer:
        return dut.wait_heartbeat(after, settle_s, state=state) is not None
    dut.frames.quiet_period(lambda m: False, settle_s)  # no event shows the state: the profile's settle time
    return False


def period_seen_s(dut: DeviceLink) -> float | None:
    """The producer's period as the newest two heartbeats of the log show it (None: fewer than two)."""
    beats = dut.frames.before(dut.frames.mark(), lambda m: is_state_beat(dut, m), LOOK_BACK)
    return beats[-1].timestamp - beats[-2].timestamp if len(beats) >= 2 else None


def since_last_command(dut: DeviceLink) -> tuple[int | None, int | None]:
    """(the newest NMT command sent to the node, the state the newest heartbeat after it reports); None for either
    where the log holds none."""
    frames = dut.frames.before(dut.frames.mark(), lambda m: _is_command(dut, m) or is_state_beat(dut, m), LOOK_BACK)
    commands = [n for n, m in enumerate(frames) if not m.is_rx]
    last = commands[-1] if commands else -1
    beats = frames[last + 1:]
    return (frames[last].data[0] if last >= 0 else None), (beats[-1].data[0] if beats else None)


def may_be_stopped(dut: DeviceLink) -> bool:
    """True where the heartbeat after the newest NMT command reports stopped, or, without a heartbeat since, that
    command was stop (only NMT stop leads there, CiA 301 v4.2.0 §7.3.2.2)."""
    command, state = since_last_command(dut)
    if state is not None:
        return state == NmtState.STOPPED
    return command == NmtCommand.STOP


def leave_stopped(dut: DeviceLink) -> bool:
    """SDO is offered: the device is not in stopped, or it left it on NMT enter pre-operational as its heartbeat
    shows (7Fh). False where it may be in stopped and no heartbeat shows it left: a caller that needs SDO resets
    communication instead (and waits for the boot-up)."""
    if not may_be_stopped(dut):
        return True
    period = period_seen_s(dut)
    if period is None:
        return False
    mark = send_command(dut, "pre-operational")
    window = state_window_s(dut, period * 1000)
    return wait_state(dut, mark, NmtState.PRE_OPERATIONAL, window) == NmtState.PRE_OPERATIONAL
