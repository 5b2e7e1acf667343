"""The values a profile declares an entry accepts, shared by the simulator and the suites.

declared domain = type range ∩ [min, max] ∩ allowed (∩ capabilities.tpdo_transmission_types for
the transmission type, 1800h..19FFh sub 2). A device that enforces the domain refuses every
value outside it; ``probe_values`` are the values just outside each boundary that a test writes.
"""

from __future__ import annotations

from encoder_conformance.basis import Basis
from encoder_conformance.cia.cia301 import RESERVED_TRANSMISSION_TYPES
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.profile.value_set import ValueSet

TPDO_COMMUNICATION = range(0x1800, 0x1A00)
TRANSMISSION_TYPE_SUB = 2
#: what says a reserved transmission type is refused, whatever the profile lists
RESERVED_TYPES_CLAUSE = "CiA 301 §7.5.2.37 table 72 (18xxh sub 2: transmission types 241..251 are reserved)"


def declared_domain(profile: DeviceProfile, index: int, sub: int) -> ValueSet | None:
    """The values ``index``/``sub`` accepts; None for undeclared entries and non-integer types."""
    entry = profile.entry(index, sub)
    if entry is None:
        return None
    limits = datatypes.value_range(entry.type)
    if limits is None:
        return None
    low = limits[0] if entry.min is None else max(limits[0], entry.min)
    high = limits[1] if entry.max is None else min(limits[1], entry.max)
    domain = ValueSet.span(low, high)
    if entry.value_set is not None:
        domain &= entry.value_set
    if index in TPDO_COMMUNICATION and sub == TRANSMISSION_TYPE_SUB:
        types = profile.capabilities.tpdo_transmission_types
        domain &= ValueSet(tuple((t, t) for t in types))
    return domain


def probe_values(profile: DeviceProfile, index: int, sub: int) -> list[int]:
    """Values just outside the declared domain (inside the type range); empty when nothing is excluded."""
    domain = declared_domain(profile, index, sub)
    entry = profile.entry(index, sub)
    if domain is None or entry is None:
        return []
    limits = datatypes.value_range(entry.type)
    assert limits is not None  # declared_domain returned a set, so the type is an integer type
    return domain.probes(*limits)


def refusal_basis(profile: DeviceProfile, index: int, sub: int, value: int) -> tuple[Basis, str]:
    """What says ``value`` (outside the declared domain) must be refused, and the profile key that holds it.

    The entry's own min/max/allowed rest on its ``domain_basis``; a transmission type refused only
    because capabilities.tpdo_transmission_types leaves it out rests on
    ``tpdo_transmission_types_refusal``, a reserved one (241..251) on CiA 301. Where both exclude the value,
    the stronger basis counts.
    """
    entry = profile.entry(index, sub)
    assert entry is not None, f"{index:04X}h.{sub:02X} is not declared"
    where = f"objects {index:04X}h.{sub:02X} min/max/allowed (domain_basis: {entry.domain_basis})"
    limits = datatypes.value_range(entry.type)
    if limits is None:
        return entry.domain_basis, where
    own = ValueSet.span(limits[0] if entry.min is None else entry.min, limits[1] if entry.max is None else entry.max)
    if entry.value_set is not None:
        own &= entry.value_set
    if value not in own and entry.domain_basis != "inferred":
        return entry.domain_basis, where
    if index in TPDO_COMMUNICATION and sub == TRANSMISSION_TYPE_SUB and value in RESERVED_TRANSMISSION_TYPES:
        return "cia", RESERVED_TYPES_CLAUSE
    if index in TPDO_COMMUNICATION and sub == TRANSMISSION_TYPE_SUB:
        basis = profile.capabilities.tpdo_transmission_types_refusal
        if basis != "inferred" or value in own:
            return basis, f"capabilities.tpdo_transmission_types (refusal: {basis})"
    return "inferred", where if value not in own else "capabilities.tpdo_transmission_types (refusal: inferred)"
