"""PDO COB-ID rules of a conformant device (CiA 301 §7.5.2.35 and §7.5.2.37, §7.3.5): a write to 14xxh/18xxh sub 1 that
changes bits 0-29 while the PDO is valid is refused, and so is a valid COB-ID with a restricted CAN-ID.

A behaviour: a write gate on the PDO communication objects' sub 1. Both refusals answer 06090030h (value
range of parameter exceeded): CiA 301 names no code, CANopenNode and the CTT (restricted IDs) use it.
Its variant ``pdo_config_refused_in_operational`` refuses every write to a PDO's communication or mapping
parameters in operational with 08000022h (present device state), as the WDGA manual's device does (M §8.5.1);
``pdo_params_fixed_while_valid`` refuses a change of a TPDO's inhibit time (sub 3) or SYNC start value (sub 6)
while the TPDO is valid (06090030h, as CANopenNode does); ``valid_pdo_needs_a_mapping`` refuses a valid COB-ID
while the PDO maps nothing (06090030h, as CANopenNode does).
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.cia.cia301 import (
    COB_ID_FIXED_WHILE_VALID,
    COB_ID_FRAME_29_BIT,
    COB_ID_INVALID,
    PDO_MAPPING_OFFSET,
    RPDO_COMMUNICATION,
    RPDO_MAPPING,
    TPDO_COMMUNICATION,
    TPDO_MAPPING,
    SdoAbortCode,
    is_restricted_can_id,
)
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.sdo_server import SdoAbort


class PdoCobIdRules:
    """Refuses the COB-ID writes CiA 301 forbids; ``read`` gives the entry's current value."""

    def __init__(self, read: Callable[[int, int], int | None],
                 state: Callable[[], NmtState | None] = lambda: None) -> None:
        self._read = read
        self._state = state

    def register(self, hooks: NodeHooks) -> None:
        hooks.gates.append(self.gate)

    def gate(self, key: Key, value: Value) -> None:
        index, sub = key
        if self.refused_in_state(index):
            raise SdoAbort(SdoAbortCode.WRONG_STATE)
        if index in TPDO_COMMUNICATION and sub in (3, 6) and self.fixed_while_pdo_valid(index):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        if sub != 1 or not isinstance(value, int) or not (index in TPDO_COMMUNICATION or index in RPDO_COMMUNICATION):
            return
        current = self._read(index, 1)
        if not value & COB_ID_INVALID and self.needs_a_mapping(index):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        if current is not None and self.fixed_while_valid(current, value):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        if self.restricted(value):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)

    def fixed_while_pdo_valid(self, index: int) -> bool:
        """Sub 3 (inhibit time) or sub 6 (SYNC start value) of a valid TPDO may not change (default twin: they may)."""
        return False

    def needs_a_mapping(self, index: int) -> bool:
        """A PDO that maps nothing may not be made valid (the default twin: it may)."""
        return False

    def refused_in_state(self, index: int) -> bool:
        """A write to a PDO parameter refused in the present NMT state (the default twin: never)."""
        return False

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


@breaks(PdoCobIdRules, "pdo_config_refused_in_operational")
class PdoConfigRefusedInOperational(PdoCobIdRules):
    """A variant, not a fault: PDO communication and mapping parameters are written in pre-operational only."""

    def refused_in_state(self, index: int) -> bool:
        pdo = any(index in area for area in (TPDO_COMMUNICATION, TPDO_MAPPING, RPDO_COMMUNICATION, RPDO_MAPPING))
        return pdo and self._state() is NmtState.OPERATIONAL


@breaks(PdoCobIdRules, "pdo_params_fixed_while_valid")
class PdoParamsFixedWhileValid(PdoCobIdRules):
    """A variant, not a fault: a TPDO's inhibit time and SYNC start value change only while the TPDO is not valid."""

    def fixed_while_pdo_valid(self, index: int) -> bool:
        cob_id = self._read(index, 1)
        return cob_id is not None and not cob_id & COB_ID_INVALID


@breaks(PdoCobIdRules, "valid_pdo_needs_a_mapping")
class ValidPdoNeedsAMapping(PdoCobIdRules):
    """A variant, not a fault: a PDO whose mapping's sub 0 is 0 is not made valid."""

    def needs_a_mapping(self, index: int) -> bool:
        return self._read(index + PDO_MAPPING_OFFSET, 0) == 0
