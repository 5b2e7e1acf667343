"""The twin's LSS behaviour: the LSS slave, and what its configuration does to the node.

Registers the slave for the LSS master's frames (7E5h, answered in the NMT states the profile allows:
quirk ``lss_only_in_states``), tells the NMT slave which node-ID a (re)start takes (``node_id_after``),
and starts an unconfigured node (node-ID 255) once it has a valid node-ID: when switched back to the
waiting state (CiA 305) or at once (quirk ``unconfigured_node_id`` with ``bootup_after_valid_node_id``).
Activate bit timing is modelled on the bus the twin sits on: silent for the switch delay, then at the
pending bit rate, silent again; at a rate other than the bus's the node hears nothing and is not heard
(``hears``/``may_send``) until a power-on brings back the stored rate.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from encoder_conformance.cia.cia301 import NmtState
from encoder_conformance.cia.cia305 import AUTO_BIT_RATE_INDEX, MAX_NODE_ID, SLAVE_COB_ID
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile, resolve_node_id_expression
from encoder_conformance.sim.engine.faults import FaultSet, assemble, breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, ReloadEvent
from encoder_conformance.sim.engine.lss_configuration import LssConfiguration
from encoder_conformance.sim.engine.lss_slave import LssSlave
from encoder_conformance.sim.engine.nmt_slave import NmtSlave
from encoder_conformance.sim.engine.nvm import NonVolatileMemory
from encoder_conformance.sim.engine.object_store import ObjectStore
from encoder_conformance.sim.engine.sim_log import log

_STATES = {"pre-operational": NmtState.PRE_OPERATIONAL, "operational": NmtState.OPERATIONAL,
           "stopped": NmtState.STOPPED}


class LssBehaviour:
    """One node's LSS: slave, configuration, and the unconfigured start."""

    def __init__(
        self,
        profile: DeviceProfile,
        nvm: NonVolatileMemory,
        store: ObjectStore,
        nmt: NmtSlave,
        address: Callable[[], tuple[int, int, int, int]],
        send: Callable[[int, bytes], None],
        faults: FaultSet,
    ) -> None:
        self._nmt = nmt
        self._store = store
        self.config = assemble(LssConfiguration, faults).for_profile(profile, nvm, nmt.node_id)
        only_in = profile.params_of(fx.LssOnlyInStates)
        self._states = None if only_in is None else frozenset(_STATES[name] for name in only_in.states)
        self._unconfigured = profile.params_of(fx.UnconfiguredNodeId)
        rate = profile.bus.bitrate
        table = profile.bus.lss_table()
        self._bus_index = next((i for i, r in table.items() if r == rate), None)  # None: the node follows any rate
        self._rate_index = self._bus_index
        self._switch: tuple[float, int | None] | None = None  # (when, to which index)
        self._silent_until = 0.0
        self.slave = assemble(LssSlave, faults)(
            frozenset(profile.capabilities.lss), address, lambda: nmt.node_id,
            lambda data: send(SLAVE_COB_ID, data), config=self.config, events=self, allowed=self.allowed,
            can_store="store_configuration" in profile.capabilities.lss, bit_indices=profile.bus.lss_bit_indices(),
        )

    def register(self, hooks: NodeHooks) -> None:
        hooks.lss.append(self.slave.on_frame)
        hooks.reload.append(self._power_on)

    # -- the bit rate on the bus ---------------------------------------------------------------------
    def _power_on(self, event: ReloadEvent) -> None:
        if event.name == "power_on":
            self._switch, self._silent_until = None, 0.0
            stored = self.config.nvm.get(self.config.bit_index_key)
            self._rate_index = stored if isinstance(stored, int) and self._bus_index is not None else self._bus_index

    def activate_bit_timing(self, switch_delay_s: float) -> None:
        log.info("node %d: LSS activate bit timing (table index %s) after %.0f ms", self._nmt.node_id,
                 self.config.pending_bit_index, switch_delay_s * 1000)
        now = time.monotonic()
        self._switch = (now + switch_delay_s, self.config.pending_bit_index)
        self._silent_until = now + 2 * switch_delay_s

    def _on_bus_rate(self) -> bool:
        if self._switch is not None and time.monotonic() >= self._switch[0]:
            if self._switch[1] is not None:
                self._rate_index = self._switch[1]
            self._switch = None
        return self._bus_index is None or self._rate_index in (self._bus_index, AUTO_BIT_RATE_INDEX)

    def hears(self) -> bool:
        """Frames on the bus reach the node (it runs at the bus's bit rate)."""
        return self._on_bus_rate()

    def may_send(self) -> bool:
        """The node's frames reach the bus: at its bit rate, and not within an activate bit timing delay."""
        return self._on_bus_rate() and time.monotonic() >= self._silent_until

    def allowed(self) -> bool:
        """LSS frames are obeyed in this NMT state (always while waiting for a node-ID)."""
        state = self._nmt.state
        return self._states is None or state in self._states or self._nmt.waiting_for_node_id

    def node_id_after(self, event: ReloadEvent) -> int | None:
        return self.config.node_id_after(event)

    def obeys_nmt_while_unconfigured(self, command: bytes) -> bool:
        """Whether an NMT command reaches the node while it waits for a node-ID (CiA 305: LSS starts it)."""
        return False

    # -- events from the slave ---------------------------------------------------------------------
    def configured(self, what: str) -> None:
        pending = self.config.pending_node_id if what == "node_id" else self.config.pending_bit_index
        log.info("node %d: LSS configure %s: %s pending", self._nmt.node_id, what.replace("_", "-"), pending)
        if what != "node_id":
            return
        if self._nmt.waiting_for_node_id and self._unconfigured is not None \
                and self._unconfigured.bootup_after_valid_node_id:
            self._start()

    def left_configuration(self) -> None:
        log.info("node %d: LSS waiting state (configuration left)", self._nmt.node_id)
        if self._nmt.waiting_for_node_id:
            self._start()

    def _start(self) -> None:
        """The unconfigured node got a valid node-ID: NMT initialisation continues with it."""
        node_id = self.config.take_pending_node_id()
        if node_id is None:
            return
        self._nmt.continue_initialisation()
        self.reset_cob_ids(node_id)

    def reset_cob_ids(self, node_id: int) -> None:
        """Quirk ``unconfigured_node_id``: the listed COB-IDs take their defaults for the new node-ID."""
        for key in () if self._unconfigured is None else self._unconfigured.cob_ids_reset_to_default:
            entry_key = (key.index, key.sub)
            if self._store.has(entry_key):
                default = resolve_node_id_expression(self._store.default_of(entry_key, node_id), node_id)
                if isinstance(default, int):
                    self._store.set(entry_key, default)


@breaks(LssBehaviour, "lss_obeyed_in_any_state")
class ObeyedInAnyState(LssBehaviour):
    """LSS frames are obeyed in every NMT state, also where the manual allows them only in some."""

    def allowed(self) -> bool:
        return True


@breaks(LssBehaviour, "lss_only_in_stopped")
class OnlyInStopped(LssBehaviour):
    """LSS frames are obeyed only in stopped (and while unconfigured)."""

    def allowed(self) -> bool:
        return self._nmt.state is NmtState.STOPPED or self._nmt.waiting_for_node_id


@breaks(LssBehaviour, "lss_ignored_in_stopped")
class IgnoredInStopped(LssBehaviour):
    def allowed(self) -> bool:
        return self._nmt.state is not NmtState.STOPPED and super().allowed()


@breaks(LssBehaviour, "lss_node_id_active_immediately")
class NodeIdActiveImmediately(LssBehaviour):
    """A configured node-ID (1..127) takes effect at once, not at the next reset communication."""

    def configured(self, what: str) -> None:
        super().configured(what)
        pending = self.config.pending_node_id
        if what == "node_id" and pending is not None and 1 <= pending <= MAX_NODE_ID \
                and not self._nmt.waiting_for_node_id:
            self.config.active_node_id = self._nmt.node_id = pending


@breaks(LssBehaviour, "lss_unconfigured_waits_for_reset")
class UnconfiguredWaitsForReset(LssBehaviour):
    """A variant, not a fault: an unconfigured node given a node-ID does not start when it leaves the configuration
    state; it boots with the stored node-ID at the next power-on ('a new boot-up', WDGA M §8.2.4)."""

    def left_configuration(self) -> None:
        log.info("node %d: LSS waiting state (configuration left); a new boot-up is needed", self._nmt.node_id)


@breaks(LssBehaviour, "lss_unconfigured_boots_at_nmt_reset")
class UnconfiguredBootsAtNmtReset(LssBehaviour):
    """A variant, not a fault: an unconfigured node given a node-ID stays in initialisation when it leaves the
    configuration state and boots with that node-ID at the next NMT reset (to all nodes), as lely-core does."""

    def left_configuration(self) -> None:
        log.info("node %d: LSS waiting state (configuration left); waits for an NMT reset", self._nmt.node_id)

    def obeys_nmt_while_unconfigured(self, command: bytes) -> bool:
        return self._nmt.waiting_for_node_id and command[:1] in (b"\x81", b"\x82")

    def node_id_after(self, event: ReloadEvent) -> int | None:
        if event.name in ("nmt_81h", "nmt_82h") and self._nmt.waiting_for_node_id:
            return self.config.take_pending_node_id() or super().node_id_after(event)
        return super().node_id_after(event)
