"""NMT slave (CiA 301 §7.3.2): power, boot-up, resets and the state-changing commands.

It owns the node's NMT state and node-id and tells the other behaviours through the node's hooks:
``halted`` when services stop (reset, reboot, power off), ``reload`` with what a (re)start reloads,
``booted`` after the boot-up message, ``state`` on every state change. Faults that break it are the
small classes at the bottom. A node whose node-ID is 255 (unconfigured, CiA 305) stays initialising
without a boot-up until LSS gives it a node-ID (``continue_initialisation``).
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from encoder_conformance.cia.cia301 import COMMUNICATION_AREA, HEARTBEAT_BASE
from encoder_conformance.cia.cia305 import UNCONFIGURED_NODE_ID
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, ReloadEvent
from encoder_conformance.sim.engine.nmt import TARGET, NmtCommand, NmtState
from encoder_conformance.sim.engine.object_store import ObjectStore
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler, JobHandle


def _communication_area(index: int) -> bool:
    """What NMT reset communication reloads."""
    return index in COMMUNICATION_AREA


def _everything(index: int) -> bool:
    return True


class NmtSlave:
    """The NMT state machine of one node, with power and boot."""

    def __init__(
        self,
        hooks: NodeHooks,
        store: ObjectStore,
        scheduler: DeadlineScheduler,
        send: Callable[[int, bytes], None],
        node_id_for: Callable[[ReloadEvent | None], int],
        boot_delay_s: float,
        silent_until_bus_traffic: bool,
        lock: threading.RLock,
    ) -> None:
        self._hooks = hooks
        self._lock = lock
        self._store = store
        self._scheduler = scheduler
        self._send = send
        self._node_id_for = node_id_for
        self._boot_delay_s = boot_delay_s
        self._silent_until_traffic = silent_until_bus_traffic
        self.node_id = node_id_for(None)
        self.state: NmtState | None = None  # None = powered off
        self.awaiting_traffic = False
        self._boot_job: JobHandle | None = None
        #: behaviours that may hold a state change back (the error behaviour: pre-operational instead of
        #: operational while a communication error is active); each returns the state the node enters
        self.admit: list[Callable[[NmtState], NmtState]] = []

    # -- power ---------------------------------------------------------------------------
    def power_on(self, at_once: bool = False) -> None:
        """Apply power: reload everything from NVM, then boot (or wait for bus traffic); ``at_once``: the boot
        delay has passed already (a served twin was switched on before a tester connects, as a bench device is)."""
        self._reload(ReloadEvent("power_on", everything=True))
        self.state = NmtState.INITIALISING
        self.awaiting_traffic = self._silent_until_traffic
        if not self.awaiting_traffic:
            self._schedule_boot(power_on=True, delay_s=0.0 if at_once else None)

    def power_off(self) -> None:
        self._halt()
        for listener in self._hooks.powered_off:
            listener()
        self.state = None

    def reboot(self, delay_s: float) -> None:
        """The device restarts by itself: silent while it initialises, boot-up after ``delay_s``."""
        self._halt()
        self.state = NmtState.INITIALISING
        self._reload(ReloadEvent("power_on", everything=True))
        if not self.waiting_for_node_id:
            self._boot_job = self._scheduler.call_later(delay_s, lambda: self._finish_boot(power_on=True))

    def bus_traffic_seen(self) -> bool:
        """A frame arrived: True if it only served to detect the bit rate (automatic bit-rate quirk)."""
        if not self.awaiting_traffic:
            return False
        self.awaiting_traffic = False
        self._schedule_boot(power_on=True)
        return True

    # -- NMT commands --------------------------------------------------------------------
    def addressed(self, target: int) -> bool:
        return target in (0, self.node_id)

    def obeys(self, command: NmtCommand) -> bool:
        return True

    def on_command(self, data: bytes) -> None:
        if len(data) != 2:
            return
        command, target = data
        if not self.addressed(target):
            return
        try:
            cmd = NmtCommand(command)
        except ValueError:
            return
        if not self.obeys(cmd):
            return
        if cmd is NmtCommand.RESET_NODE:
            self.reset(node=True)
        elif cmd is NmtCommand.RESET_COMMUNICATION:
            self.reset(node=False)
        else:
            self.enter(TARGET[cmd])

    def reset_reloads_everything(self, node: bool) -> bool:
        return node

    def reset_reloads(self, node: bool) -> Callable[[int], bool]:
        """The object indices a reset loads from NVM (or defaults)."""
        return _everything if self.reset_reloads_everything(node) else _communication_area

    def reset(self, node: bool) -> None:
        """NMT reset node (everything) or reset communication (1000h-1FFFh) and boot again."""
        self._halt()
        self.state = NmtState.INITIALISING
        self._reload(ReloadEvent("nmt_81h" if node else "nmt_82h", self.reset_reloads_everything(node)),
                     self.reset_reloads(node))
        self._schedule_boot(power_on=False)

    def enter(self, state: NmtState) -> None:
        for admit in self.admit:
            state = admit(state)
        previous, self.state = self.state, state
        if state is not previous:
            self._hooks.emit_state(state)

    # -- boot ----------------------------------------------------------------------------
    def sends_bootup(self, power_on: bool) -> bool:
        return True

    def starts_itself(self) -> bool:
        """After the boot-up the node stays in pre-operational (CiA 301 §7.3.2.2); a quirk's object may start it."""
        return False

    def _reload(self, event: ReloadEvent, area: Callable[[int], bool] | None = None) -> None:
        self.node_id = self._node_id_for(event)
        self._store.reload(area or (_everything if event.everything else _communication_area), self.node_id)
        self._hooks.emit_reload(event)

    def _halt(self) -> None:
        if self._boot_job is not None:
            self._boot_job.cancel()
            self._boot_job = None
        for listener in self._hooks.halted:
            listener()

    @property
    def waiting_for_node_id(self) -> bool:
        """Unconfigured (node-ID 255): initialising, no boot-up until LSS gives a node-ID."""
        return self.state is NmtState.INITIALISING and self.node_id == UNCONFIGURED_NODE_ID

    def continue_initialisation(self) -> None:
        """LSS gave the unconfigured node a node-ID: communication starts with it, then the boot-up."""
        self._reload(ReloadEvent("nmt_82h", everything=False))
        self._schedule_boot(power_on=False)

    def _schedule_boot(self, power_on: bool, delay_s: float | None = None) -> None:
        if self.waiting_for_node_id:
            return  # CiA 305: an unconfigured node waits for LSS
        delay = self._boot_delay_s if delay_s is None else delay_s
        self._boot_job = self._scheduler.call_later(delay, lambda: self._finish_boot(power_on))

    def _finish_boot(self, power_on: bool) -> None:
        with self._lock:
            if self.state is not NmtState.INITIALISING:
                return
            if self.sends_bootup(power_on):
                self._send(HEARTBEAT_BASE + self.node_id, b"\x00")
            self.enter(NmtState.PRE_OPERATIONAL)
            for listener in self._hooks.booted:
                listener()
            if self.starts_itself():
                self.enter(NmtState.OPERATIONAL)


@breaks(NmtSlave, "no_bootup_after_reset")
class SilentAfterReset(NmtSlave):
    def sends_bootup(self, power_on: bool) -> bool:
        return power_on


def _ignores(name: str, command: NmtCommand) -> type[NmtSlave]:
    """A fault that ignores one NMT command."""

    class IgnoresCommand(NmtSlave):
        def obeys(self, received: NmtCommand) -> bool:
            return received is not command and super().obeys(received)

    IgnoresCommand.__name__ = IgnoresCommand.__qualname__ = f"Ignores{command.name.title().replace('_', '')}"
    return breaks(NmtSlave, name)(IgnoresCommand)


IGNORED_COMMAND_FAULTS = [
    _ignores("ignore_start", NmtCommand.START),
    _ignores("ignore_stop", NmtCommand.STOP),
    _ignores("ignore_enter_preop", NmtCommand.ENTER_PRE_OPERATIONAL),
    _ignores("reset_comm_keeps_state", NmtCommand.RESET_COMMUNICATION),
]


@breaks(NmtSlave, "ignore_broadcast")
class IgnoresBroadcast(NmtSlave):
    def addressed(self, target: int) -> bool:
        return target != 0 and super().addressed(target)


@breaks(NmtSlave, "respond_to_other_node")
class ObeysAnyNode(NmtSlave):
    def addressed(self, target: int) -> bool:
        return True


@breaks(NmtSlave, "reset_node_keeps_values")
class ResetNodeKeepsValues(NmtSlave):
    def reset_reloads_everything(self, node: bool) -> bool:
        return False


@breaks(NmtSlave, "reset_comm_keeps_comm_values")
class ResetCommKeepsValues(NmtSlave):
    """Reset communication boots again without loading 1000h-1FFFh."""

    def reset_reloads(self, node: bool) -> Callable[[int], bool]:
        return super().reset_reloads(node) if node else (lambda index: False)


@breaks(NmtSlave, "reset_comm_reloads_application")
class ResetCommReloadsApplication(NmtSlave):
    def reset_reloads_everything(self, node: bool) -> bool:
        return True


@breaks(NmtSlave, "preop_reloads_communication")
class PreopReloadsCommunication(NmtSlave):
    """Entering pre-operational from operational or stopped loads 1000h-1FFFh again."""

    def enter(self, state: NmtState) -> None:
        if state is NmtState.PRE_OPERATIONAL and self.state in (NmtState.OPERATIONAL, NmtState.STOPPED):
            self._reload(ReloadEvent("nmt_82h", everything=False))
        super().enter(state)


@breaks(NmtSlave, "self_starts_after_reset")
class SelfStartsAfterReset(NmtSlave):
    """After every boot-up (power-on, reset node, reset communication) the node enters operational by itself."""

    def starts_itself(self) -> bool:
        return True


@breaks(NmtSlave, "lss_unconfigured_boots")
class UnconfiguredBoots(NmtSlave):
    """Node-ID 255 is taken as a node-ID like any other: the node boots with it."""

    @property
    def waiting_for_node_id(self) -> bool:
        return False
