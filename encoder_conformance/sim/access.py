"""What an SDO read or write does on the simulated node: existence, access, size, limits, effects.

Each check returns the CiA 301 abort code for its situation; faults and profile quirks change
the outcome at exactly one place each.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..profile import datatypes
from .sdo_server import SdoAbort

if TYPE_CHECKING:
    from .node import SimulatedNode

NO_OBJECT = 0x06020000
NO_SUBINDEX = 0x06090011
READ_WO = 0x06010001
WRITE_RO = 0x06010002
LENGTH_HIGH = 0x06070012
LENGTH_LOW = 0x06070013
LENGTH_MISMATCH = 0x06070010
VALUE_HIGH = 0x06090031
VALUE_LOW = 0x06090032
VALUE_INVALID = 0x06090030
CANNOT_STORE = 0x08000020
WRONG_STATE = 0x08000022
GENERAL_ERROR = 0x08000000

SAVE = 0x65766173  # 'save' little-endian
LOAD = 0x64616F6C  # 'load' little-endian


class NodeObjectAccess:
    """The ObjectAccess of one simulated node (see sdo_server.ObjectAccess)."""

    def __init__(self, node: SimulatedNode) -> None:
        self.node = node

    # -- shared checks -------------------------------------------------------------------
    def _locate(self, index: int, sub: int) -> tuple[int, int]:
        node, faults = self.node, self.node.faults
        missing_index = not node.store.has_index(index) or index in node.hidden_indices
        if missing_index:
            raise SdoAbort(NO_SUBINDEX if faults.active("wrong_abort_no_object") else NO_OBJECT)
        if not node.store.has((index, sub)):
            raise SdoAbort(NO_OBJECT if faults.active("wrong_abort_no_subindex") else NO_SUBINDEX)
        return index, sub

    # -- read ----------------------------------------------------------------------------
    def sdo_read(self, index: int, sub: int) -> bytes:
        key = self._locate(index, sub)
        node = self.node
        entry = node.store.entries[key]
        if entry.access == "wo":
            if node.faults.active("read_wo_allowed"):
                return bytes(datatypes.size_bytes(entry.type) or 1)
            raise SdoAbort(READ_WO)
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
            raise SdoAbort(GENERAL_ERROR if node.faults.active("wrong_abort_write_ro") else WRITE_RO)
        size = datatypes.size_bytes(entry.type)
        if size is not None and len(data) != size:
            raise SdoAbort(LENGTH_HIGH if len(data) > size else LENGTH_LOW)
        value = node.store.decode(key, data)
        if isinstance(value, int):
            self._check_limits(entry.min, entry.max, value)
        node.quirk_write_gate(key)
        if node.faults.active("write_rw_ignored"):
            return
        node.apply_write(key, value)

    @staticmethod
    def _check_limits(minimum: int | None, maximum: int | None, value: int) -> None:
        if maximum is not None and value > maximum:
            raise SdoAbort(VALUE_HIGH)
        if minimum is not None and value < minimum:
            raise SdoAbort(VALUE_LOW)
