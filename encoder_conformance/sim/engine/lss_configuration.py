"""What LSS configures in a twin: the node-ID and bit timing, pending, active and stored (CiA 305).

A configured node-ID is *pending* until the node applies it: on NMT reset communication (CiA 305 v3)
or, for a legacy device (quirk ``lss_only_in_states`` with ``activation: power_cycle``), only at the
next power-on from what store configuration kept. Power-on forgets everything not stored. Node-ID 255
means unconfigured: the node waits for LSS (``sim/engine/nmt_slave.py``) and starts when it gets a valid ID.

The stored values sit in the node's NVM under the manufacturer object the profile names for them
(quirks ``node_id_object``/``bitrate_object``), else under pseudo keys outside the object dictionary.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from encoder_conformance.cia.cia305 import MAX_NODE_ID, UNCONFIGURED_NODE_ID
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import ReloadEvent
from encoder_conformance.sim.engine.nvm import Key, NonVolatileMemory

#: NVM keys of the LSS-stored values on a device without a manufacturer object for them
STORED_NODE_ID = (0x0000, 0x01)
STORED_BIT_INDEX = (0x0000, 0x02)


def usable_node_id(value: object) -> int | None:
    """A stored node-ID the node can start with (1..127, or 255 = unconfigured), else None."""
    if isinstance(value, int) and (1 <= value <= MAX_NODE_ID or value == UNCONFIGURED_NODE_ID):
        return value
    return None


@dataclass
class LssConfiguration:
    """Pending, active and stored node-ID / bit timing of one node."""

    nvm: NonVolatileMemory
    node_id_key: Key = STORED_NODE_ID
    bit_index_key: Key = STORED_BIT_INDEX
    activation: str = "reset_communication"
    auto_stored: frozenset[str] = frozenset()
    pending_node_id: int | None = None
    pending_bit_index: int | None = None
    active_node_id: int | None = None  # applied by a reset since power-on
    factory: dict[Key, int] = field(default_factory=dict)  # what an empty memory stands for

    @classmethod
    def for_profile(cls, profile: DeviceProfile, nvm: NonVolatileMemory, node_id: int) -> LssConfiguration:
        node_id_object = profile.params_of(fx.NodeIdObject)
        bitrate_object = profile.params_of(fx.BitrateObject)
        states = profile.params_of(fx.LssOnlyInStates)
        auto = profile.params_of(fx.LssConfigAutoStored)
        node_id_key = STORED_NODE_ID if node_id_object is None else (node_id_object.index, node_id_object.subindex)
        bit_index_key = STORED_BIT_INDEX if bitrate_object is None else (bitrate_object.index, bitrate_object.subindex)
        factory = {node_id_key: node_id}
        for key in (node_id_key, bit_index_key):
            entry = profile.entry(*key)
            if entry is not None and isinstance(entry.default, int):
                factory[key] = entry.default
        return cls(
            nvm, node_id_key=node_id_key, bit_index_key=bit_index_key,
            activation="reset_communication" if states is None else states.activation,
            auto_stored=frozenset(() if auto is None else auto.auto_stored), factory=factory,
        )

    # -- LSS services ----------------------------------------------------------------------------
    def configure_node_id(self, node_id: int) -> None:
        self.pending_node_id = node_id
        if "node_id" in self.auto_stored:
            self._keep({self.node_id_key: node_id})

    def configure_bit_index(self, index: int) -> None:
        self.pending_bit_index = index
        if "bit_timing" in self.auto_stored:
            self._keep({self.bit_index_key: index})

    def store(self, active_node_id: int) -> bool:
        """Store configuration: the pending values (the active node-ID where none is pending)."""
        values: dict[Key, int] = {self.node_id_key: self.pending_node_id or active_node_id}
        if self.pending_bit_index is not None:
            values[self.bit_index_key] = self.pending_bit_index
        self._keep(values)
        return True

    def _keep(self, values: dict[Key, int]) -> None:
        """Write what differs from the memory. The twin's memory shows a cell holding its factory value as
        empty, so a stored factory value empties the cell (the device reads the same either way)."""
        changed = {key: value for key, value in values.items()
                   if value != (self.nvm.get(key) if key in self.nvm else self.factory.get(key))}
        back_to_factory = [key for key, value in changed.items() if self.factory.get(key) == value]
        if back_to_factory:
            self.nvm.remove_many(back_to_factory)
        rest = {key: value for key, value in changed.items() if key not in back_to_factory}
        if rest:
            self.nvm.put_many(rest)

    # -- what the node starts with ------------------------------------------------------------------
    def stored_node_id(self) -> int | None:
        return usable_node_id(self.nvm.get(self.node_id_key))

    def node_id_after(self, event: ReloadEvent) -> int | None:
        """The node-ID LSS gives the node after ``event`` (None: LSS has no say)."""
        if event.name == "power_on":
            self.pending_node_id = self.pending_bit_index = self.active_node_id = None
            return self.stored_node_id()
        if self.applies_on_reset() and self.pending_node_id is not None:
            self.active_node_id, self.pending_node_id = self.pending_node_id, None
        return self.active_node_id

    def applies_on_reset(self) -> bool:
        return self.activation == "reset_communication"

    def take_pending_node_id(self) -> int | None:
        """An unconfigured node takes the pending node-ID at once (it is not running yet)."""
        node_id, self.pending_node_id = self.pending_node_id, None
        if node_id is not None and 1 <= node_id <= MAX_NODE_ID:
            self.active_node_id = node_id
            return node_id
        return None


@breaks(LssConfiguration, "lss_store_not_persisted")
class StoreNotPersisted(LssConfiguration):
    """Store configuration answers success and keeps nothing."""

    def store(self, active_node_id: int) -> bool:
        return True


@breaks(LssConfiguration, "lss_auto_store_ignored")
class AutoStoreIgnored(LssConfiguration):
    """Nothing is stored by itself: a configured node-ID is lost at power-off unless stored by 17h."""

    def configure_node_id(self, node_id: int) -> None:
        self.pending_node_id = node_id


@breaks(LssConfiguration, "lss_node_id_at_reset_comm")
class NodeIdAtResetCommunication(LssConfiguration):
    """A variant, not a fault: a configured node-ID becomes active at NMT reset communication (CiA 305 v3), also
    where the profile's manual applies it at power-on (a 'new boot-up', WDGA M §8.2.4)."""

    def applies_on_reset(self) -> bool:
        return True
