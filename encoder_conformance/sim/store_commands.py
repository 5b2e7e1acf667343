"""What writes to store objects do on a simulated node: 1010h 'save', 1011h 'load' and the quirks
that replace or add to them (``store_reboots_without_reply``, ``store_automatic``,
``node_id_object`` with a store object of its own).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..cia301 import LOAD_SIGNATURE, SAVE_SIGNATURE
from .nvm import Key
from .object_store import SUB_TO_GROUP
from .sdo_server import SdoAbort, SdoNoReply
from .store_variants import ManufacturerStoreObject, ParameterSets

if TYPE_CHECKING:
    from .node import SimulatedNode


def _key(params: dict[str, Any], index: str, sub: str, default: Key) -> Key:
    return int(params.get(index, default[0])), int(params.get(sub, default[1]))


class StoreCommands:
    """The store and restore behaviour of one node, as its profile declares it."""

    def __init__(self, node: SimulatedNode) -> None:
        self.node = node
        self.reboot = node.quirk_params("store_reboots_without_reply")
        self.automatic = node.quirk_params("store_automatic") is not None
        extra = node.quirk_params("manufacturer_store_object")
        self.extra_store = None if extra is None else ManufacturerStoreObject.from_params(extra)
        sets = node.quirk_params("reload_immediate")
        self.sets = None if sets is None else ParameterSets.from_params(sets)

    def on_write(self, key: Key, value: object) -> bool:
        """Carry out a store/restore command; True when ``key`` was one (the value is not kept)."""
        if self.reboot is not None and key == _key(self.reboot, "index", "subindex", (0x1010, 1)):
            self._store_and_reboot(value, self.reboot)
        if self.extra_store is not None and key == self.extra_store.key:
            self._manufacturer_store(value, self.extra_store)
            return True
        if self.sets is not None and self.sets.handles(key):
            self._parameter_set_command(key, value, self.sets)
            return True
        if key[0] in (0x1010, 0x1011):
            self._store_or_restore(key[0], key[1], value)
            return True
        return False

    def after_write(self, key: Key, value: object) -> None:
        """A value was written: persist it if the device does that by itself."""
        store = self.node.store
        if self.node.faults.active("store_not_persisted"):
            return
        store.persist_auto(key)
        if self.automatic:
            store.persist(key)

    def _check_signature(self, value: object, signature: int, abort_code: int | None = None) -> None:
        node = self.node
        if value != signature and not node.faults.active("store_wrong_signature_accepted"):
            raise SdoAbort(node.access.codes["store_signature"] if abort_code is None else abort_code)

    def _manufacturer_store(self, value: object, command: ManufacturerStoreObject) -> None:
        """Quirk manufacturer_store_object: its own 'save' persists its objects (effective after reset)."""
        self._check_signature(value, command.signature, command.wrong_signature_abort)
        node = self.node
        if not node.faults.active("manufacturer_store_not_persisted"):
            node.store.nvm.put_many({k: node.store.get(k) for k in command.saves if node.store.has(k)})  # type: ignore[misc]

    def _parameter_set_command(self, key: Key, value: object, sets: ParameterSets) -> None:
        """Quirk reload_immediate: save a parameter set, or load saved values at once (no reset)."""
        index, sub = key
        self._check_signature(value, SAVE_SIGNATURE if index == 0x1010 else LOAD_SIGNATURE)
        node = self.node
        if index == 0x1010:
            sets.save_set(sub, node.store, node.nvm)
        elif not node.faults.active("reload_not_immediate"):
            sets.reload(sub, node.store, node.nvm, node.default_value, self._keys_stored_by)

    def _keys_stored_by(self, store_sub: int) -> list[Key]:
        """The entries 1010h ``store_sub`` writes to NVM."""
        return self.node.store.storable_keys(SUB_TO_GROUP.get(store_sub, "store_manufacturer"))

    def _store_or_restore(self, index: int, sub: int, value: object) -> None:
        node = self.node
        storing = index == 0x1010
        self._check_signature(value, SAVE_SIGNATURE if storing else LOAD_SIGNATURE)
        group = SUB_TO_GROUP.get(sub, "store_manufacturer")
        if storing:
            if not node.faults.active("store_not_persisted"):
                node.store.store(group)
                node.encoder.persist(node.nvm)
        elif not node.faults.active("restore_ineffective"):
            node.store.restore_defaults(group)
            node.encoder.forget(node.nvm)

    def _store_and_reboot(self, value: object, params: dict[str, Any]) -> None:
        """Quirk store_reboots_without_reply: store everything, no SDO reply, reboot, boot-up later.

        Any other value than the signature is refused (params.wrong_signature_abort, default the
        CiA 'cannot store' code) and changes nothing: the manual leaves this case open.
        """
        node = self.node
        wrong = params.get("wrong_signature_abort")
        signature = int(params.get("signature_u32", SAVE_SIGNATURE))
        self._check_signature(value, signature, None if wrong is None else int(wrong))
        if not node.faults.active("store_not_persisted"):
            node.store.store_all_storable()
            node.encoder.persist(node.nvm)
        node.reboot(float(params.get("reboot_ms", node.profile.simulator.bootup_delay_ms)) / 1000)
        raise SdoNoReply
