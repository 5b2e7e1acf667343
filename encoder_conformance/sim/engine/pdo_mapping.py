"""PDO mapping rules (CiA 301 §7.5.2.38 TPDO, §7.5.2.36 RPDO): when and what a mapping object accepts.

The mapping changes only in the CiA 301 procedure: PDO invalid (COB-ID bit 31) where its COB-ID is
writable, sub 0 = 0, the entries, sub 0 = n. An entry must name an object that exists (06020000h) and is
PDO-mappable in the profile (06040041h), or a dummy data type the profile declares
(``capabilities.pdo_dummy_mapping``); sub 0 = n refuses entries of more than 64 bits in all (06040042h).
An entry or sub 0 written out of order is refused with 06090030h, as CANopenNode and lely answer
(CiA 301 names no code for it; FAULHABER Tab. 6 documents 06090030h too). Not checked: an entry's length
against its object's size (WDGA documents a 64-bit object mapped with 32 bits). A behaviour: it
registers a write gate; faults that break it are the small classes at the bottom.
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.cia.cia301 import (
    COB_ID_INVALID,
    DUMMY_BITS,
    DUMMY_INDICES,
    PDO_MAPPING_OFFSET,
    PDO_MAX_BITS,
    RPDO_MAPPING,
    TPDO_MAPPING,
    SdoAbortCode,
    mapping_fields,
)
from encoder_conformance.profile.quirk_effects import MappingChangeWhileValid
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.sdo_server import SdoAbort


def is_mapping_object(index: int) -> bool:
    return index in TPDO_MAPPING or index in RPDO_MAPPING


class MappingRules:
    """Refuses mapping writes outside the procedure and mappings CiA 301 does not allow."""

    def __init__(self, profile: DeviceProfile, read: Callable[[int, int], int | None],
                 codes: dict[str, int]) -> None:
        self._profile = profile
        self._read = read
        self._no_object = codes["no_object"]
        self._dummies = frozenset(profile.capabilities.pdo_dummy_mapping)
        # quirk mapping_change_while_valid: the manual's procedure never makes the PDO invalid
        self._valid_pdo_open = profile.has_effect(MappingChangeWhileValid)

    def register(self, hooks: NodeHooks) -> None:
        hooks.gates.append(self.gate)

    def gate(self, key: Key, value: Value) -> None:
        index, sub = key
        if not is_mapping_object(index) or not isinstance(value, int):
            return
        if self.pdo_valid(index - PDO_MAPPING_OFFSET):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        if sub == 0:
            if value:
                self.check_length(index, value)
            return
        if self.entries_locked(index):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        if value:  # 0: an empty entry
            self.check_entry(*mapping_fields(value))

    def pdo_valid(self, comm: int) -> bool:
        """The PDO is valid (COB-ID bit 31 clear) and could be made invalid (its COB-ID is writable), and the
        profile documents no procedure without invalidating it."""
        if self._valid_pdo_open:
            return False
        entry = self._profile.entry(comm, 1)
        cob_id = self._read(comm, 1)
        return entry is not None and entry.writable and cob_id is not None and not cob_id & COB_ID_INVALID

    def entries_locked(self, mapping: int) -> bool:
        """Entries change only while sub 0 = 0 (mapping disabled)."""
        return bool(self._read(mapping, 0))

    def check_entry(self, index: int, sub: int, bits: int) -> None:
        if index in DUMMY_INDICES and sub == 0:
            if index not in self._dummies or bits != DUMMY_BITS[index]:
                raise SdoAbort(SdoAbortCode.NOT_MAPPABLE)
            return
        entry = self._profile.entry(index, sub)
        if not self.exists(index, sub):
            raise SdoAbort(self._no_object)
        if not self.mappable(entry):
            raise SdoAbort(SdoAbortCode.NOT_MAPPABLE)

    def exists(self, index: int, sub: int) -> bool:
        return self._profile.entry(index, sub) is not None

    def mappable(self, entry: object) -> bool:
        return bool(getattr(entry, "pdo_mappable", False))

    def check_length(self, mapping: int, count: int) -> None:
        """sub 0 = ``count``: those entries exist and carry at most 64 bits."""
        words = [self._read(mapping, sub) for sub in range(1, count + 1)]
        if any(word is None for word in words):
            raise SdoAbort(SdoAbortCode.VALUE_HIGH)  # more entries than the object has
        if sum(mapping_fields(word)[2] for word in words if word) > self.max_bits():
            raise SdoAbort(SdoAbortCode.PDO_TOO_LONG)

    def max_bits(self) -> int:
        return PDO_MAX_BITS


@breaks(MappingRules, "mapping_accepted_while_valid")
class AcceptedWhileValid(MappingRules):
    def pdo_valid(self, comm: int) -> bool:
        return False


@breaks(MappingRules, "mapping_change_while_valid_refused")
class DocumentedProcedureRefused(MappingRules):
    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._valid_pdo_open = False  # quirk mapping_change_while_valid ignored: the CiA rule after all


@breaks(MappingRules, "mapping_entries_while_enabled_count")
class EntriesWhileEnabled(MappingRules):
    def entries_locked(self, mapping: int) -> bool:
        return False


@breaks(MappingRules, "non_mappable_object_accepted")
class NonMappableAccepted(MappingRules):
    def mappable(self, entry: object) -> bool:
        return True


@breaks(MappingRules, "missing_object_mapped")
class MissingObjectMapped(MappingRules):
    def exists(self, index: int, sub: int) -> bool:
        return True

    def mappable(self, entry: object) -> bool:
        return entry is None or super().mappable(entry)  # an absent object has no mapping flag to refuse


@breaks(MappingRules, "mapping_length_unchecked")
class LengthUnchecked(MappingRules):
    def max_bits(self) -> int:
        return 8 * 0xFF * 8
