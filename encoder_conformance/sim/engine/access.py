"""The SDO access rules of a simulated node: existence, access, size and value domain (CiA 301).

Each check answers with the CiA 301 abort code for its situation; a quirk with effect
``abort_code`` replaces the code of its situation by the first code it lists. A write the rules
accept goes on through the node's hooks (gates, commands, reactions: ``sim/engine/hooks.py``). Faults that
break a rule are the small classes at the bottom, each overriding one decision.
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.cia.cia301 import (
    ABORT_FOR_SITUATION,
    ERROR_HISTORY,
    RESERVED_TRANSMISSION_TYPES,
    RPDO_MAPPING,
    TPDO_COMMUNICATION,
    TPDO_MAPPING,
)
from encoder_conformance.cia.cia301 import SdoAbortCode as Abort
from encoder_conformance.profile import datatypes
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.profile.value_domain import declared_domain, refusal_basis
from encoder_conformance.profile.value_set import ValueSet
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.object_store import ObjectStore
from encoder_conformance.sim.engine.sdo_server import SdoAbort


def situation_codes(profile: DeviceProfile) -> dict[str, int]:
    """The code the device sends per situation: CiA's, or the first one an ``abort_code`` quirk lists."""
    codes = dict(ABORT_FOR_SITUATION)
    for quirk in profile.quirks.values():
        if isinstance(quirk.params, fx.AbortCode):
            codes[quirk.params.situation] = quirk.params.codes[0]
    return codes


class ObjectAccess:
    """The sdo_server.ObjectAccess of one simulated node."""

    def __init__(self, profile: DeviceProfile, store: ObjectStore, hooks: NodeHooks,
                 encode: Callable[[Key], bytes], codes: dict[str, int]) -> None:
        self._profile = profile
        self._store = store
        self._hooks = hooks
        self._encode = encode
        self.codes = codes
        self._domains: dict[Key, ValueSet | None] = {}

    # -- shared checks -------------------------------------------------------------------
    def exists(self, index: int) -> bool:
        return self._store.has_index(index)

    def no_object_code(self) -> int:
        return self.codes["no_object"]

    def no_subindex_code(self) -> int:
        return self.codes["no_subindex"]

    def _locate(self, index: int, sub: int) -> Key:
        if not self.exists(index):
            raise SdoAbort(self.no_object_code())
        if not self._store.has((index, sub)):
            raise SdoAbort(self.no_subindex_code())
        return index, sub

    # -- read ----------------------------------------------------------------------------
    def read_write_only(self, entry_type: str) -> bytes:
        raise SdoAbort(self.codes["read_wo"])

    def encoded(self, key: Key) -> bytes:
        return self._encode(key)

    def sdo_read(self, index: int, sub: int) -> bytes:
        key = self._locate(index, sub)
        entry = self._store.entries[key]
        if entry.no_data:  # present without data (the profile says so): CiA 301 table 22
            raise SdoAbort(Abort.NO_DATA)
        if entry.access == "wo":
            return self.read_write_only(entry.type)
        return self.encoded(key)

    # -- write ---------------------------------------------------------------------------
    def write_read_only(self) -> None:
        raise SdoAbort(self.codes["write_ro"])

    def sdo_write(self, index: int, sub: int, data: bytes) -> None:
        key = self._locate(index, sub)
        entry = self._store.entries[key]
        if entry.no_data:
            raise SdoAbort(Abort.NO_DATA)
        if entry.access in ("ro", "const"):
            self.write_read_only()
            return
        data = self.sized(key, data)
        value = self._store.decode(key, data)
        if isinstance(value, int):
            self.check_domain(key, value)
        for gate in self._hooks.gates:
            gate(key, value)
        self.accept(key, value)

    def declared_size(self, index: int, sub: int) -> int | None:
        """Bytes of the entry's data type (None: a string, a domain, or no such entry)."""
        entry = self._store.entries.get((index, sub))
        return None if entry is None else datatypes.size_bytes(entry.type)

    def sized(self, key: Key, data: bytes) -> bytes:
        """The written data, refused (06070012h / 06070013h) where its length is not the data type's."""
        size = datatypes.size_bytes(self._store.entries[key].type)
        if size is not None and len(data) != size:
            raise SdoAbort(self.codes["length_high"] if len(data) > size else self.codes["length_low"])
        return data

    def accept(self, key: Key, value: Value) -> None:
        """The write passed every check: a command consumes it, or it is stored and reacted to."""
        hooks = self._hooks
        if any(command(key, value) for command in hooks.commands):
            return
        for reaction in hooks.before_set:
            reaction(key, value)
        self._store.set(key, value)
        hooks.written(key, value)

    def check_domain(self, key: Key, value: int) -> None:
        """Refuse a value outside the declared domain (type range, min/max, allowed, TPDO types)."""
        if key not in self._domains:
            self._domains[key] = declared_domain(self._profile, *key)
        domain = self._domains[key]
        if domain is None or value in domain:
            return
        if domain.maximum is not None and value > domain.maximum:
            raise SdoAbort(self.codes["value_high"])
        if domain.minimum is not None and value < domain.minimum:
            raise SdoAbort(self.codes["value_low"])
        raise SdoAbort(Abort.VALUE_INVALID)  # in a gap of the allowed values (or nothing is allowed)


@breaks(ObjectAccess, "missing_object")
class LastObjectMissing(ObjectAccess):
    """The last declared object of the profile does not exist."""

    def exists(self, index: int) -> bool:
        return index != max(self._profile.objects) and super().exists(index)


@breaks(ObjectAccess, "wrong_abort_no_object")
class WrongAbortNoObject(ObjectAccess):
    def no_object_code(self) -> int:
        return Abort.NO_SUBINDEX


@breaks(ObjectAccess, "wrong_abort_no_subindex")
class WrongAbortNoSubindex(ObjectAccess):
    def no_subindex_code(self) -> int:
        return Abort.NO_OBJECT


@breaks(ObjectAccess, "read_wo_allowed")
class WriteOnlyReadable(ObjectAccess):
    def read_write_only(self, entry_type: str) -> bytes:
        return bytes(datatypes.size_bytes(entry_type) or 1)


@breaks(ObjectAccess, "wrong_size")
class ShortUploads(ObjectAccess):
    """Expedited uploads of 32-bit objects carry 2 bytes."""

    def encoded(self, key: Key) -> bytes:
        data = super().encoded(key)
        if len(data) == 4 and self._store.entries[key].type not in datatypes.STRING_TYPES:
            return data[:2]
        return data


@breaks(ObjectAccess, "size_mismatch_accepted")
class SizeMismatchAccepted(ObjectAccess):
    """Writes with more or fewer bytes than the data type are confirmed (cut or zero-padded to its size)."""

    def sized(self, key: Key, data: bytes) -> bytes:
        size = datatypes.size_bytes(self._store.entries[key].type)
        return data if size is None else data[:size].ljust(size, b"\x00")


@breaks(ObjectAccess, "write_ro_accepted")
class ReadOnlyWritable(ObjectAccess):
    def write_read_only(self) -> None:
        return  # confirmed, and ignored


@breaks(ObjectAccess, "wrong_abort_write_ro")
class WrongAbortWriteReadOnly(ObjectAccess):
    def write_read_only(self) -> None:
        raise SdoAbort(Abort.GENERAL_ERROR)


@breaks(ObjectAccess, "write_ro_unsupported_access")
class UnsupportedAccessWriteReadOnly(ObjectAccess):
    """A variant: 06010000h (unsupported access) instead of 06010002h (attempt to write a read only object)."""

    def write_read_only(self) -> None:
        raise SdoAbort(Abort.UNSUPPORTED_ACCESS)


@breaks(ObjectAccess, "value_domain_ignored")
class ValueDomainIgnored(ObjectAccess):
    def check_domain(self, key: Key, value: int) -> None:
        return


@breaks(ObjectAccess, "cia301_transmission_types")
class Cia301TransmissionTypes(ObjectAccess):
    """A variant, not a fault: every transmission type CiA 301 defines is accepted (0..240, 252..255), where only
    our inference refuses it (a type the manual itself excludes, e.g. a documented range, stays refused)."""

    def check_domain(self, key: Key, value: int) -> None:
        index, sub = key
        if (0x1800 <= index <= 0x19FF and sub == 2 and (value <= 240 or value >= 252)
                and refusal_basis(self._profile, index, sub, value)[0] == "inferred"):
            return
        super().check_domain(key, value)


@breaks(ObjectAccess, "empty_history_no_data")
class EmptyHistoryNoData(ObjectAccess):
    """A variant, not a fault: an entry of the error history 1003h above its count (sub 0) is empty, and a read
    of it answers 08000024h (no data available), as CANopenNode does."""

    def sdo_read(self, index: int, sub: int) -> bytes:
        recorded = index == ERROR_HISTORY and self._store.has((index, sub)) and self._store.has((index, 0))
        if recorded and sub > int(self._store.get((ERROR_HISTORY, 0))):
            raise SdoAbort(Abort.NO_DATA)
        return super().sdo_read(index, sub)


@breaks(ObjectAccess, "reserved_transmission_types_accepted")
class ReservedTransmissionTypesAccepted(ObjectAccess):
    """18xxh sub 2 takes the transmission types CiA 301 reserves (241..251); the TPDO then never sends."""

    def check_domain(self, key: Key, value: int) -> None:
        if key[0] in TPDO_COMMUNICATION and key[1] == 2 and value in RESERVED_TRANSMISSION_TYPES:
            return
        super().check_domain(key, value)


@breaks(ObjectAccess, "empty_arrays")
class EmptyArrays(ObjectAccess):
    """A variant, not a fault: an ARRAY from 2000h on with a read-only sub 0 holds as many elements as sub 0 counts;
    an upload or download of an element above the count answers 08000024h (no data available), as a stack does
    that loaded an EDS without a sub 0 DefaultValue (CiA 306): sub 0 is then 0 and no element holds data."""

    def _empty(self, index: int, sub: int) -> bool:
        obj = self._profile.objects.get(index)
        if index < 0x2000 or sub == 0 or obj is None or obj.object_kind != "array" or not self._store.has((index, sub)):
            return False
        count = obj.entry_table.get(0)
        return count is not None and count.access in ("ro", "const") and sub > int(self._store.get((index, 0)))

    def sdo_read(self, index: int, sub: int) -> bytes:
        if self._empty(index, sub):
            raise SdoAbort(Abort.NO_DATA)
        return super().sdo_read(index, sub)

    def sdo_write(self, index: int, sub: int, data: bytes) -> None:
        if self._empty(index, sub):
            raise SdoAbort(Abort.NO_DATA)
        super().sdo_write(index, sub, data)


@breaks(ObjectAccess, "write_rw_ignored")
class WritesIgnored(ObjectAccess):
    def accept(self, key: Key, value: Value) -> None:
        return  # confirmed, value unchanged


@breaks(ObjectAccess, "fixed_mapping_writable")
class FixedMappingWritable(ObjectAccess):
    """Read-only PDO mapping entries (a fixed mapping) accept writes and change; a device without mapping
    objects (a fixed payload) confirms writes to them."""

    def sdo_write(self, index: int, sub: int, data: bytes) -> None:
        key = (index, sub)
        mapping = index in TPDO_MAPPING or index in RPDO_MAPPING
        if mapping and not self.exists(index):
            return  # confirmed, and nothing there to change
        entry = self._store.entries.get(key)
        if entry is not None and entry.access in ("ro", "const") and mapping:
            self.accept(key, self._store.decode(key, data))
            return
        super().sdo_write(index, sub, data)
