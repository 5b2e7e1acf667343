"""The simulated node's object dictionary: current values, encoding, reload from NVM or defaults."""

from __future__ import annotations

from collections.abc import Callable

import canopen
from canopen.objectdictionary import ODVariable

from encoder_conformance.cia.cia301 import TPDO_MAPPING
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.od_builder import build_object_dictionary, initial_value
from encoder_conformance.profile.quirk_effects import RestoreExcludes
from encoder_conformance.profile.schema import DeviceProfile, EntrySpec, resolve_node_id_expression
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.nvm import Key, NonVolatileMemory

#: persisted_by labels a 1010h sub stores; the profile's label decides (devices differ in the
#: ranges their subs cover, e.g. FAULHABER's "application" sub covers 2000h..6FFFh)
STORE_GROUPS = ("store_all", "store_comm", "store_app", "store_manufacturer")
#: CiA 301 1010h/1011h sub-index -> group it covers (sub 4+ are manufacturer-defined).
SUB_TO_GROUP = {1: "store_all", 2: "store_comm", 3: "store_app", 4: "store_manufacturer"}


class ObjectStore:
    """Values of every profile entry, with canopen's encode/decode for the wire format."""

    def __init__(self, profile: DeviceProfile, nvm: NonVolatileMemory, node_id: int) -> None:
        self.profile = profile
        self.nvm = nvm
        self.od: canopen.ObjectDictionary = build_object_dictionary(profile, node_id)
        self.entries: dict[Key, EntrySpec] = {
            (index, sub): entry for index, sub, _, entry in profile.iter_entries()
        }
        self.values: dict[Key, int | float | str | bytes] = {}
        excluded = profile.params_of(RestoreExcludes)
        self.restore_excluded = excluded.indices if excluded else frozenset()
        self.reload(lambda index: True, node_id)

    # -- lookup --------------------------------------------------------------------------
    def has_index(self, index: int) -> bool:
        return index in self.profile.objects

    def has(self, key: Key) -> bool:
        return key in self.entries

    def variable(self, key: Key) -> ODVariable:
        obj = self.od[key[0]]
        return obj if isinstance(obj, ODVariable) else obj[key[1]]

    def size(self, key: Key) -> int | None:
        """Fixed size in bytes, None for strings/domains."""
        return datatypes.size_bytes(self.entries[key].type)

    # -- values --------------------------------------------------------------------------
    def get(self, key: Key) -> int | float | str | bytes:
        return self.values[key]

    def set(self, key: Key, value: int | float | str | bytes) -> None:
        self.values[key] = value

    def encode(self, key: Key) -> bytes:
        value = self.values[key]
        if isinstance(value, bytes):
            return value
        if isinstance(value, str):
            return datatypes.string_bytes(self.entries[key].type, value)
        return self.variable(key).encode_raw(value)

    def decode(self, key: Key, data: bytes) -> int | float | str | bytes:
        entry = self.entries[key]
        if entry.type == "VISIBLE_STRING":
            return data.decode("latin-1")
        if entry.type in datatypes.STRING_TYPES:
            return bytes(data)
        value = self.variable(key).decode_raw(data)
        # canopen hands back the data itself for a type it cannot unpack: as bytes, like the string types above
        return bytes(value) if isinstance(value, bytearray) else value

    # -- persistence ---------------------------------------------------------------------
    def default_of(self, key: Key, node_id: int) -> int | str:
        entry = self.entries[key]
        return initial_value(self.profile, key[0], key[1], entry, node_id)

    def reload(self, in_scope: Callable[[int], bool], node_id: int) -> None:
        """Set every entry in scope to its stored value, else its (node-id resolved) default."""
        for key, entry in self.entries.items():
            if not in_scope(key[0]):
                continue
            stored = self.nvm.get(key)
            if stored is not None and entry.persisted_by != "none":
                self.values[key] = stored
            else:
                self.values[key] = resolve_node_id_expression(self.default_of(key, node_id), node_id)

    def storable_keys(self, group: str) -> list[Key]:
        """Entries that 1010h with ``group`` writes to NVM: those labelled so (store_all: every store_* label)."""
        return [
            key
            for key, entry in self.entries.items()
            if entry.writable and entry.persisted_by in STORE_GROUPS
            and (group == "store_all" or entry.persisted_by == group)
        ]

    def nvm_values(self, keys: list[Key]) -> dict[Key, int | float | str]:
        """The current values of ``keys``, less those NVM does not keep (bytes)."""
        values: dict[Key, int | float | str] = {}
        for key in keys:
            value = self.values[key]
            if not isinstance(value, bytes):
                values[key] = value
        return values

    def store(self, group: str) -> None:
        keys = self.storable_keys(group)
        self.nvm.put_many(self.nvm_values(keys))

    def store_all_storable(self) -> None:
        """Write every storable entry (store_* groups and manufacturer_store) to NVM at once."""
        storable = ("store_all", "store_comm", "store_app", "store_manufacturer", "manufacturer_store")
        keys = [key for key, entry in self.entries.items() if entry.writable and entry.persisted_by in storable]
        self.nvm.put_many(self.nvm_values(keys))

    def persist(self, key: Key) -> None:
        """Write one entry to NVM now (quirk store_automatic), unless it cannot be stored."""
        value = self.values[key]
        if self.entries[key].persisted_by not in ("none", "volatile") and not isinstance(value, bytes):
            self.nvm.put_many({key: value})

    def restore_defaults(self, group: str) -> None:
        """Forget stored values of the group; defaults become active at the next reset.

        Restore-all also covers what the device stores by itself (persisted_by: auto), except the
        objects a ``restore_excludes`` quirk lists.
        """
        keys = self.storable_keys(group)
        if group == "store_all":
            keys += [key for key, entry in self.entries.items() if entry.writable and entry.persisted_by == "auto"]
        self.nvm.remove_many([key for key in keys if key[0] not in self.restore_excluded])

    def persist_auto(self, key: Key) -> None:
        """Entries with persisted_by: auto go to NVM on every write."""
        value = self.values[key]
        if self.entries[key].persisted_by == "auto" and not isinstance(value, bytes):
            self.nvm.put_many({key: value})


@breaks(ObjectStore, "wrong_default")
class WrongDefaults(ObjectStore):
    """Every reload leaves writable UNSIGNED values one above their factory default."""

    def reload(self, in_scope: Callable[[int], bool], node_id: int) -> None:
        super().reload(in_scope, node_id)
        for key, entry in self.entries.items():
            value = self.values[key]
            default = resolve_node_id_expression(self.default_of(key, node_id), node_id)
            if (entry.writable and isinstance(value, int) and value == default and entry.type.startswith("UNSIGNED")
                    and key[0] not in (0x1010, 0x1011)):
                self.values[key] = value + 1


@breaks(ObjectStore, "tpdo_mappings_empty")
class TpdoMappingsEmpty(ObjectStore):
    """Every reload leaves every TPDO mapping empty (sub 0 = 0): the device lost its default mapping."""

    def reload(self, in_scope: Callable[[int], bool], node_id: int) -> None:
        super().reload(in_scope, node_id)
        for mapping in TPDO_MAPPING:
            if (mapping, 0) in self.values and in_scope(mapping):
                self.values[(mapping, 0)] = 0


@breaks(ObjectStore, "default_mapping_wrong_length")
class DefaultMappingWrongLength(ObjectStore):
    """Every reload leaves the first TPDO mapping entry 8 bits longer than its object (e.g. 60040028h)."""

    def reload(self, in_scope: Callable[[int], bool], node_id: int) -> None:
        super().reload(in_scope, node_id)
        for mapping in TPDO_MAPPING:
            value = self.values.get((mapping, 1))
            if isinstance(value, int) and value and in_scope(mapping):
                self.values[(mapping, 1)] = (value & ~0xFF) | ((value & 0xFF) + 8) & 0xFF
                return
