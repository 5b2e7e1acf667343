"""What an SDO read or write does on the simulated node: existence, access, size, limits, effects.

Each check returns the CiA 301 abort code for its situation; faults and profile quirks change
the outcome at exactly one place each. A quirk with effect ``abort_code`` replaces the code of
its situation by the first code it lists.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..cia301 import ABORT_FOR_SITUATION
from ..cia301 import SdoAbortCode as Abort
from ..profile import datatypes
from ..profile.model import DeviceProfile
from ..profile.value_set import ValueSet
from ..value_domain import declared_domain
from .sdo_server import SdoAbort

if TYPE_CHECKING:
    from .node import SimulatedNode

def situation_codes(profile: DeviceProfile) -> dict[str, int]:
    """The code the device sends per situation: CiA's, or the first one an ``abort_code`` quirk lists."""
    codes = dict(ABORT_FOR_SITUATION)
    for quirk in profile.quirks.values():
        listed = quirk.params.get("codes") or []
        if quirk.effect == "abort_code" and quirk.params.get("situation") in codes and listed:
            codes[quirk.params["situation"]] = int(listed[0])
    return codes


class NodeObjectAccess:
    """The ObjectAccess of one simulated node (see sdo_server.ObjectAccess)."""

    def __init__(self, node: SimulatedNode) -> None:
        self.node = node
        self.codes = situation_codes(node.profile)
        self._domains: dict[tuple[int, int], ValueSet | None] = {}

    # -- shared checks -------------------------------------------------------------------
    def _locate(self, index: int, sub: int) -> tuple[int, int]:
        node, faults = self.node, self.node.faults
        missing_index = not node.store.has_index(index) or index in node.hidden_indices
        if missing_index:
            raise SdoAbort(Abort.NO_SUBINDEX if faults.active("wrong_abort_no_object") else self.codes["no_object"])
        if not node.store.has((index, sub)):
            raise SdoAbort(Abort.NO_OBJECT if faults.active("wrong_abort_no_subindex") else self.codes["no_subindex"])
        return index, sub

    # -- read ----------------------------------------------------------------------------
    def sdo_read(self, index: int, sub: int) -> bytes:
        key = self._locate(index, sub)
        node = self.node
        entry = node.store.entries[key]
        if entry.access == "wo":
            if node.faults.active("read_wo_allowed"):
                return bytes(datatypes.size_bytes(entry.type) or 1)
            raise SdoAbort(self.codes["read_wo"])
        data = node.encode_current(key)
        if node.faults.active("wrong_size") and len(data) == 4 and entry.type not in datatypes.STRING_TYPES:
            data = data[:2]
        return data

    # -- write ---------------------------------------------------------------------------
    def sdo_write(self, index: int, sub: int, data: bytes) -> None:
        key = self._locate(index, sub)
        node = self.node
        entry = node.store.entries[key]
        if entry.access in ("ro", "const"):
            if node.faults.active("write_ro_accepted"):
                return
            wrong = node.faults.active("wrong_abort_write_ro")
            raise SdoAbort(Abort.GENERAL_ERROR if wrong else self.codes["write_ro"])
        size = datatypes.size_bytes(entry.type)
        if size is not None and len(data) != size:
            raise SdoAbort(self.codes["length_high"] if len(data) > size else self.codes["length_low"])
        value = node.store.decode(key, data)
        if isinstance(value, int) and not node.faults.active("value_domain_ignored"):
            self._check_domain(key, value)
        node.quirk_write_gate(key, value)
        if node.faults.active("write_rw_ignored"):
            return
        node.apply_write(key, value)

    def _check_domain(self, key: tuple[int, int], value: int) -> None:
        """Refuse a value outside the declared domain (type range, min/max, allowed, TPDO types)."""
        if key not in self._domains:
            self._domains[key] = declared_domain(self.node.profile, *key)
        domain = self._domains[key]
        if domain is None or value in domain:
            return
        if domain.maximum is not None and value > domain.maximum:
            raise SdoAbort(self.codes["value_high"])
        if domain.minimum is not None and value < domain.minimum:
            raise SdoAbort(self.codes["value_low"])
        raise SdoAbort(Abort.VALUE_INVALID)  # in a gap of the allowed values (or nothing is allowed)
