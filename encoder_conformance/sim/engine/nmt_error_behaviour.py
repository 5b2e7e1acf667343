"""What an error does to the NMT state (CiA 301 v4.2.0 §7.2.8.3.1 error behaviour; object 1029h).

A behaviour that the default twin keeps idle: an error with the communication bit of 1001h (bit 4: a heartbeat
consumer time-out 8130h, a SYNC of the wrong length 8240h, a SYNC time-out 8100h) leaves the NMT state as it is.
Its variants play the other reading CiA 301 allows (its default error behaviour: from operational to
pre-operational), as CANopenNode does: while the error is active the node leaves operational within a millisecond,
also at an NMT start (the node stays in pre-operational: the heartbeat never shows operational); a reset
(communication or node) clears 1001h and with it the error.

``StartUpFailure``: what the node finds wrong when it starts: nothing on the default twin. Its variant plays a
device failure present at every start (CANopenNode's Linux demo without its storage files): after each boot-up an
EMCY 5000h with 1001h bit 0, which no reset clears (another error going away leaves it in 1001h and in the error
reset EMCY), and while it is there the node does not enter operational (CiA 301's default error behaviour for a
device failure; the heartbeat never shows operational). Its second variant refuses NMT start as a whole: a node
started from stopped stays stopped (no SDO there, CiA 301 §7.3.2.2).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Protocol

from encoder_conformance.cia.cia301 import ERROR_REGISTER, ERROR_REGISTER_GENERIC, EmcyCode
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler
from encoder_conformance.sim.engine.sync_objects import COMMUNICATION_ERROR_BIT, Read


class Nmt(Protocol):
    """What the behaviour needs of the NMT slave."""

    state: NmtState | None
    admit: list

    def enter(self, state: NmtState) -> None: ...


class CommErrorBehaviour:
    """Sends the node to pre-operational while a communication error is active, where a variant says so."""

    def __init__(self, scheduler: DeadlineScheduler, read: Read, nmt: Nmt, lock: threading.RLock) -> None:
        self._scheduler = scheduler
        self._read = read
        self._nmt = nmt
        self._lock = lock

    def register(self, hooks: NodeHooks) -> None:
        self._nmt.admit.append(self.admit)

    def leaves_operational(self) -> bool:
        """CiA 301's default error behaviour for a communication error (the default twin: keep the state)."""
        return False

    def admit(self, state: NmtState) -> NmtState:
        """The state an NMT command leads to: pre-operational instead of operational while the error is active."""
        if state is NmtState.OPERATIONAL and self.leaves_operational() and self._active():
            return NmtState.PRE_OPERATIONAL
        return state

    def after_error(self, register_bits: int) -> None:
        """An error was recorded (``register_bits`` of 1001h)."""
        if register_bits & COMMUNICATION_ERROR_BIT:
            self.check()

    def check(self) -> None:
        """Called with the node's lock held (the error was just recorded): leave operational at once."""
        if self.leaves_operational() and self._active() and self._nmt.state is NmtState.OPERATIONAL:
            self._nmt.enter(NmtState.PRE_OPERATIONAL)

    def _active(self) -> bool:
        return bool((self._read(ERROR_REGISTER, 0) or 0) & COMMUNICATION_ERROR_BIT)


@breaks(CommErrorBehaviour, "comm_error_enters_preoperational")
class CommErrorEntersPreoperational(CommErrorBehaviour):
    """A variant, not a fault: a communication error sends the node from operational to pre-operational."""

    def leaves_operational(self) -> bool:
        return True



class StartUpFailure:
    """A device failure found at each start-up: none (the default twin); see the module's docstring."""

    def __init__(self, raise_error: Callable[[int, int], None], nmt: Nmt) -> None:
        self._raise_error = raise_error
        self._nmt = nmt

    def register(self, hooks: NodeHooks) -> None:
        hooks.booted.append(self.after_boot)
        hooks.present_errors.append(self.present)
        self._nmt.admit.append(self.admit)

    def failed_at_start(self) -> bool:
        return False

    def present(self) -> int:
        """1001h bits of the failure while it is there (an error reset keeps them)."""
        return ERROR_REGISTER_GENERIC if self.failed_at_start() else 0

    def after_boot(self) -> None:
        """Right after the boot-up: the failure's EMCY and 1001h, at every start (power-on and both resets)."""
        if self.failed_at_start():
            self._raise_error(EmcyCode.DEVICE_HARDWARE, ERROR_REGISTER_GENERIC)

    def admit(self, state: NmtState) -> NmtState:
        """While the failure is there, NMT start leaves the node in pre-operational."""
        return NmtState.PRE_OPERATIONAL if state is NmtState.OPERATIONAL and self.failed_at_start() else state


@breaks(StartUpFailure, "device_error_at_start")
class FailsAtEveryStart(StartUpFailure):
    """A variant, not a fault: a device failure at every start-up that no reset clears."""

    def failed_at_start(self) -> bool:
        return True


@breaks(StartUpFailure, "device_error_at_start_stays_stopped")
class FailsAndRefusesStart(FailsAtEveryStart):
    """A variant, not a fault: the same failure, and NMT start refused as a whole: the node stays where it is."""

    def admit(self, state: NmtState) -> NmtState:
        if state is NmtState.OPERATIONAL and self._nmt.state is not None:
            return self._nmt.state
        return super().admit(state)
