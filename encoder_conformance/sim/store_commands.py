"""What writes to store objects do on a simulated node: 1010h 'save', 1011h 'load' and the quirks
that replace or add to them (``store_reboots_without_reply``, ``store_automatic``,
``node_id_object`` with a store object of its own).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from . import access as codes
from .nvm import Key
from .object_store import SUB_TO_GROUP
from .sdo_server import SdoAbort, SdoNoReply

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
        node_id = node.quirk_params("node_id_object")
        self.node_id_store = node_id if node_id and "store_index" in node_id else None

    def on_write(self, key: Key, value: object) -> bool:
        """Carry out a store/restore command; True when ``key`` was one (the value is not kept)."""
        if self.reboot is not None and key == _key(self.reboot, "index", "subindex", (0x1010, 1)):
            self._store_and_reboot(value, self.reboot)
        if key[0] in (0x1010, 0x1011):
            self._store_or_restore(key[0], key[1], value)
            return True
        return False

    def after_write(self, key: Key, value: object) -> None:
        """A value was written: persist it if the device does that by itself."""
        store = self.node.store
        store.persist_auto(key)
        if self.automatic:
            store.persist(key)
        params = self.node_id_store
        if (params and key == _key(params, "store_index", "store_subindex", (0, 0))
                and value == int(params.get("store_signature", codes.SAVE))):
            node_id_key = _key(params, "index", "subindex", (0, 0))
            store.nvm.put_many({node_id_key: store.get(node_id_key)})  # effective after the next reset

    def _store_or_restore(self, index: int, sub: int, value: object) -> None:
        node = self.node
        storing = index == 0x1010
        signature = codes.SAVE if storing else codes.LOAD
        if value != signature and not node.faults.active("store_wrong_signature_accepted"):
            raise SdoAbort(node.access.codes["store_signature"])
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
        signature = int(params.get("signature_u32", codes.SAVE))
        if value != signature and not node.faults.active("store_wrong_signature_accepted"):
            raise SdoAbort(int(params.get("wrong_signature_abort", node.access.codes["store_signature"])))
        if not node.faults.active("store_not_persisted"):
            node.store.store_all_storable()
            node.encoder.persist(node.nvm)
        node.reboot(float(params.get("reboot_ms", node.profile.simulator.bootup_delay_ms)) / 1000)
        raise SdoNoReply
