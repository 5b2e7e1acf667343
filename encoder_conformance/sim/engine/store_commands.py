"""What writes to store objects do on a simulated node: 1010h 'save', 1011h 'load' and the quirks
that replace or add to them (``store_reboots_without_reply``, ``store_automatic``,
``manufacturer_store_object``, ``reload_immediate``).

A behaviour: it registers the store objects as commands and persists what the device stores by
itself after each write. Faults that break it are the small classes at the bottom.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from encoder_conformance.cia.cia301 import LOAD_SIGNATURE, SAVE_SIGNATURE
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks
from encoder_conformance.sim.engine.nvm import Key, NonVolatileMemory
from encoder_conformance.sim.engine.object_store import SUB_TO_GROUP, ObjectStore
from encoder_conformance.sim.engine.sdo_server import SdoAbort, SdoNoReply
from encoder_conformance.sim.engine.store_variants import ManufacturerStoreObject, ParameterSets


@dataclass(frozen=True)
class EncoderMemory:
    """What the encoder function keeps in NVM besides objects (the preset offset, with the preset object)."""

    persist: Callable[[NonVolatileMemory, list[Key] | None], None]
    forget: Callable[[NonVolatileMemory, list[Key] | None], None]


class StoreCommands:
    """The store and restore behaviour of one node, as its profile declares it."""

    def __init__(self, profile: DeviceProfile, store: ObjectStore, encoder: EncoderMemory,
                 reboot: Callable[[float], None], default_value: Callable[[Key], Any], codes: dict[str, int]) -> None:
        self._profile = profile
        self._store = store
        self._nvm = store.nvm
        self._encoder = encoder
        self._reboot = reboot
        self._default_value = default_value
        self._codes = codes
        self.reboot = profile.params_of(fx.StoreRebootsWithoutReply)
        self.automatic = profile.has_effect(fx.StoreAutomatic)
        extra = profile.params_of(fx.ManufacturerStoreObject)
        self.extra_store = None if extra is None else ManufacturerStoreObject.from_params(extra)
        sets = profile.params_of(fx.ReloadImmediate)
        self.sets = None if sets is None else ParameterSets.from_params(sets)

    def register(self, hooks: NodeHooks) -> None:
        hooks.commands.append(self.on_write)
        hooks.on_written(self.after_write)

    def on_write(self, key: Key, value: object) -> bool:
        """Carry out a store/restore command; True when ``key`` was one (the value is not kept)."""
        if self.reboot is not None and key == self.reboot.key:
            self._store_and_reboot(value, self.reboot)
            return True  # confirmed: only a device that answers the command (fault store_reboot_confirmed)
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

    def persists(self) -> bool:
        """Whether storing keeps anything (a fault makes it confirm and keep nothing)."""
        return True

    def after_write(self, key: Key, value: object) -> None:
        """A value was written: persist it if the device does that by itself."""
        if not self.persists():
            return
        self._store.persist_auto(key)
        if self.automatic:
            self._store.persist(key)
        if self.automatic or self._store.entries[key].persisted_by == "auto":
            self._encoder.persist(self._nvm, [key])  # a preset object that stores itself keeps its offset

    def signature_accepted(self, value: object, signature: int) -> bool:
        return value == signature

    def _check_signature(self, value: object, signature: int, abort_code: int | None = None) -> None:
        if not self.signature_accepted(value, signature):
            raise SdoAbort(self._codes["store_signature"] if abort_code is None else abort_code)

    def _manufacturer_store(self, value: object, command: ManufacturerStoreObject) -> None:
        """Quirk manufacturer_store_object: its own 'save' persists its objects (effective after reset)."""
        self._check_signature(value, command.signature, command.wrong_signature_abort)
        self.save_manufacturer(command)

    def save_manufacturer(self, command: ManufacturerStoreObject) -> None:
        store = self._store
        # unlike ObjectStore.store, bytes (an OCTET_STRING/DOMAIN object) are not left out, though NVM's JSON file
        # cannot hold them (no profile saves one so far; leaving them out would change what the twin does)
        self._nvm.put_many({k: store.get(k) for k in command.saves if store.has(k)})  # type: ignore[misc]  # why: above

    def _parameter_set_command(self, key: Key, value: object, sets: ParameterSets) -> None:
        """Quirk reload_immediate: save a parameter set, or load saved values at once (no reset)."""
        index, sub = key
        self._check_signature(value, SAVE_SIGNATURE if index == 0x1010 else LOAD_SIGNATURE)
        if index == 0x1010:
            sets.save_set(sub, self._store, self._nvm)
        else:
            self.load_set(sub, sets)

    def load_set(self, sub: int, sets: ParameterSets) -> None:
        sets.reload(sub, self._store, self._nvm, self._default_value, self._keys_stored_by)

    def _keys_stored_by(self, store_sub: int) -> list[Key]:
        """The entries 1010h ``store_sub`` writes to NVM."""
        return self._store.storable_keys(SUB_TO_GROUP.get(store_sub, "store_manufacturer"))

    def _store_or_restore(self, index: int, sub: int, value: object) -> None:
        storing = index == 0x1010
        self._check_signature(value, SAVE_SIGNATURE if storing else LOAD_SIGNATURE)
        group = SUB_TO_GROUP.get(sub, "store_manufacturer")
        if storing:
            if self.persists():
                self._store.store(group)
                self._encoder.persist(self._nvm, self._store.storable_keys(group))
        else:
            self.restore_defaults(group)

    def restore_defaults(self, group: str) -> None:
        self._store.restore_defaults(group)
        self._encoder.forget(self._nvm, None if group == "store_all" else self._store.storable_keys(group))

    def _store_and_reboot(self, value: object, params: fx.StoreRebootsWithoutReply) -> None:
        """Quirk store_reboots_without_reply: store everything, no SDO reply, reboot, boot-up later.

        Any other value than the signature is refused (params.wrong_signature_abort, default the
        CiA 'cannot store' code) and changes nothing: the manual leaves this case open.
        """
        self._check_signature(value, params.signature_u32, params.wrong_signature_abort)
        if self.persists():
            self._store.store_all_storable()
            self._encoder.persist(self._nvm, None)
        reboot_ms = self._profile.simulator.bootup_delay_ms if params.reboot_ms is None else params.reboot_ms
        self._reboot(reboot_ms / 1000)
        if not self.confirms_store_by_reboot():
            raise SdoNoReply

    def confirms_store_by_reboot(self) -> bool:
        """The manual's store-by-reboot command gets no SDO reply."""
        return False


@breaks(StoreCommands, "store_not_persisted")
class StoreNotPersisted(StoreCommands):
    def persists(self) -> bool:
        return False


@breaks(StoreCommands, "store_wrong_signature_accepted")
class AnySignature(StoreCommands):
    def signature_accepted(self, value: object, signature: int) -> bool:
        return True


@breaks(StoreCommands, "restore_ineffective")
class RestoreIneffective(StoreCommands):
    def restore_defaults(self, group: str) -> None:
        return  # confirmed; the stored values survive the next reset


@breaks(StoreCommands, "reload_not_immediate")
class ReloadNotImmediate(StoreCommands):
    def load_set(self, sub: int, sets: ParameterSets) -> None:
        return  # the values become current only after a reset


@breaks(StoreCommands, "store_reboot_confirmed")
class StoreRebootConfirmed(StoreCommands):
    def confirms_store_by_reboot(self) -> bool:
        return True  # an SDO download confirmation, then the reboot


@breaks(StoreCommands, "manufacturer_store_not_persisted")
class ManufacturerStoreNotPersisted(StoreCommands):
    def save_manufacturer(self, command: ManufacturerStoreObject) -> None:
        return
