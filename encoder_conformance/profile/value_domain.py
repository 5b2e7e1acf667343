"""The values a profile declares an entry accepts, shared by the simulator and the suites.

declared domain = type range ∩ [min, max] ∩ allowed (∩ capabilities.tpdo_transmission_types for
the transmission type, 1800h..19FFh sub 2). A device that enforces the domain refuses every
value outside it; ``probe_values`` are the values just outside each boundary that a test writes.
"""

from __future__ import annotations

from . import datatypes
from .model import DeviceProfile
from .value_set import ValueSet

TPDO_COMMUNICATION = range(0x1800, 0x1A00)
TRANSMISSION_TYPE_SUB = 2


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
