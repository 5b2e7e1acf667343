"""PDO COB-ID rules of a conformant device (CiA 301 §7.5.2.35, §7.3.5): a write to 14xxh/18xxh sub 1 that
changes bits 0-29 while the PDO is valid is refused, and so is a valid COB-ID with a restricted CAN-ID.

A behaviour: a write gate on the PDO communication objects' sub 1. Both refusals answer 06090030h (value
range of parameter exceeded): CiA 301 names no code, CANopenNode and the CTT (restricted IDs) use it.
"""

from __future__ import annotations

from collections.abc import Callable

from ..cia301 import (
    COB_ID_FIXED_WHILE_VALID,
    COB_ID_FRAME_29_BIT,
    COB_ID_INVALID,
    RPDO_COMMUNICATION,
    TPDO_COMMUNICATION,
    SdoAbortCode,
    is_restricted_can_id,
)
from .faults import breaks
from .hooks import NodeHooks, Value
from .nvm import Key
from .sdo_server import SdoAbort


class PdoCobIdRules:
    """Refuses the COB-ID writes CiA 301 forbids; ``read`` gives the entry's current value."""

    def __init__(self, read: Callable[[int, int], int | None]) -> None:
        self._read = read

    def register(self, hooks: NodeHooks) -> None:
        hooks.gates.append(self.gate)

    def gate(self, key: Key, value: Value) -> None:
        index, sub = key
        if sub != 1 or not isinstance(value, int) or not (index in TPDO_COMMUNICATION or index in RPDO_COMMUNICATION):
            return
        current = self._read(index, 1)
        if current is not None and self.fixed_while_valid(current, value):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        if self.restricted(value):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)

    def fixed_while_valid(self, current: int, new: int) -> bool:
        """Bits 0-29 change while the PDO exists (bit 31 = 0)."""
        return not current & COB_ID_INVALID and bool((current ^ new) & COB_ID_FIXED_WHILE_VALID)

    def restricted(self, new: int) -> bool:
        """A valid 11-bit COB-ID with a restricted CAN-ID."""
        return not new & (COB_ID_INVALID | COB_ID_FRAME_29_BIT) and is_restricted_can_id(new & 0x7FF)


@breaks(PdoCobIdRules, "cob_id_change_while_valid_accepted")
class CobIdChangeWhileValid(PdoCobIdRules):
    def fixed_while_valid(self, current: int, new: int) -> bool:
        return False


@breaks(PdoCobIdRules, "restricted_cob_id_accepted")
class RestrictedCobIdAccepted(PdoCobIdRules):
    def restricted(self, new: int) -> bool:
        return False
