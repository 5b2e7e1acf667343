"""Pick parameters a test may change safely, and a value to change them to, from the profile."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from encoder_conformance.profile import datatypes
from encoder_conformance.profile.quirk_effects import BitrateObject, NodeIdObject
from encoder_conformance.profile.schema import DeviceProfile, EntrySpec
from encoder_conformance.profile.value_domain import declared_domain

STORE_GROUPS = ("store_all", "store_comm", "store_app", "store_manufacturer")


def _addressing(index: int) -> bool:
    """COB-IDs and PDO/SDO parameters: changing them can collide with other nodes on a real bus."""
    return index in (0x1005, 0x1012, 0x1014) or 0x1200 <= index <= 0x1BFF


@dataclass(frozen=True)
class Changeable:
    index: int
    sub: int
    entry: EntrySpec
    new_value: int

    @property
    def label(self) -> str:
        return f"{self.index:04X}h.{self.sub:02X} {self.entry.name}"


def _other_value(profile: DeviceProfile, index: int, sub: int, entry: EntrySpec) -> int | None:
    """A valid value different from the default (a harmless heartbeat period for 1017h)."""
    if not isinstance(entry.default, int):
        return None
    if index == 0x1017:
        value: int | None = max(entry.default + 1, 10 * profile.timing.heartbeat_test_period_ms)
    else:
        limits = datatypes.value_range(entry.type)
        top = entry.max if entry.max is not None else (limits[1] if limits else None)
        value = entry.default + 1 if top is not None and entry.default + 1 <= top else None
    domain = declared_domain(profile, index, sub)  # also min/max's gaps: allowed, TPDO types
    return None if value is not None and domain is not None and value not in domain else value


def changeable_parameter(
    profile: DeviceProfile, wanted: Callable[[int, EntrySpec], bool], prefer: tuple[int, ...] = ()
) -> Changeable | None:
    """The first rw integer entry with a default that ``wanted`` accepts (``prefer`` indices first)."""
    entries = profile.iter_entries()
    ordered = [e for e in entries if e[0] in prefer] + [e for e in entries if e[0] not in prefer]
    for index, sub, _, entry in ordered:
        if not (entry.writable and entry.readable) or index in (0x1010, 0x1011) or _addressing(index):
            continue
        if not wanted(index, entry):
            continue
        if any(isinstance(q.params, (NodeIdObject, BitrateObject)) and q.params.index == index
               for q in profile.quirks.values()):
            continue  # never move the device to another node-id or bit rate
        value = _other_value(profile, index, sub, entry)
        if value is not None:
            return Changeable(index, sub, entry, value)
    return None


def other_valid_value(profile: DeviceProfile, index: int, sub: int, current: int) -> int | None:
    """A value next to ``current`` inside the entry's declared domain (None if there is none)."""
    domain = declared_domain(profile, index, sub)
    return next((c for c in (current + 1, current - 1) if domain is not None and c in domain), None)
