"""``dut.nmt``: the NMT commands the tester sends and the states reached by transition, each seen by what the state
answers (the heartbeat's state byte), as labgrid's ``Strategy.transition()`` reaches a state by one call that knows
the way and checks arrival."""

from __future__ import annotations

import can

import encoder_conformance.dut.nmt.commands as commands
import encoder_conformance.dut.nmt.heartbeat_state as heartbeat_state
import encoder_conformance.dut.nmt.nmt_states as nmt_states
from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.link.notes import Notes
from encoder_conformance.dut.nmt.nmt_frames import target_state

#: the states ``transition`` reaches
STATES = tuple(nmt_states.STATES)


class NmtFace:
    """The device's NMT: commands (``command``, the resets) and the way into a state (``transition``)."""

    def __init__(self, dut: DeviceLink) -> None:
        self._dut = dut

    def command(self, name: str, node_id: int | None = None) -> Mark:
        """Send NMT command ``name`` (start, stop, pre-operational, reset-node, reset-communication) to the device,
        or to ``node_id`` (0: all nodes); a mark before it. A test of the command itself judges what follows."""
        return commands.send_command(self._dut, name, node_id)

    def transition(self, state: str, journal: SettingsJournal, notes: Notes) -> None:
        """Bring the device into ``state`` (pre-operational, operational, stopped) from wherever it is, and see it
        there by its heartbeat (switched on through ``journal`` where it is off). AssertionError naming the state
        observed where it did not get there; operational not reached while the device keeps an error reset
        communication does not clear is not testable (``HeldByPersistentError``)."""
        if state not in nmt_states.STATES:
            raise ValueError(f"unknown NMT state {state!r}: one of {', '.join(STATES)}")
        if state == "operational":
            nmt_states.start_operational(self._dut, journal, notes)
        else:
            nmt_states.reach(self._dut, journal, notes, state)

    def settle(self, after: Mark, command: str) -> bool:
        """After NMT ``command`` sent at ``after``: until the heartbeat reports the state it leads to, at most the
        profile's settle time (``heartbeat_state.settle``); True once it did. Judges nothing: a test that needs the
        state seen uses ``transition`` or ``confirm``."""
        return heartbeat_state.settle(self._dut, after, target_state(command))

    def back_to_preoperational(self, period_ms: int | None = None) -> None:
        """The put-back after a test: NMT enter pre-operational, seen in the heartbeat where ``period_ms`` (1017h)
        is known, else by SDO answering (``nmt_states.return_to_preoperational``)."""
        nmt_states.return_to_preoperational(self._dut, period_ms)

    def confirm(self, after: Mark, state: int, period_ms: float, why: str) -> None:
        """A heartbeat after ``after`` reports ``state``; else AssertionError naming the state it reports."""
        nmt_states.confirm(self._dut, after, state, period_ms, why)

    def reset_node(self) -> can.Message:
        """NMT reset node; the boot-up frame, or AssertionError with the trace."""
        return commands.reset_node_and_wait(self._dut)

    def reset_and_reach(self) -> bool:
        """NMT reset node; True once a boot-up or an SDO answer shows the node is there."""
        return commands.reset_and_reach(self._dut)
