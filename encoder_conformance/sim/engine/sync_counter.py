"""The SYNC counter overflow value 1019h (CiA 301 §7.5.2.18): 0 (SYNC without counter) or 2..240 (the
counter's overflow); 1 and 241..255 are reserved and refused (06090030h), and a write while 1006h (the
communication cycle period) is not 0 is refused in that state (CiA's wrong-state code).

A behaviour: a write gate on 1019h. The counter itself travels in the SYNC frame; the node hands it to
the SYNC listeners (the TPDO engine's SYNC start value, sim/engine/tpdo.py).
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.cia.cia301 import (
    COMMUNICATION_CYCLE_PERIOD,
    SYNC_COUNTER_OVERFLOW,
    SYNC_COUNTER_OVERFLOW_VALID,
    SdoAbortCode,
)
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.sdo_server import SdoAbort


class SyncCounterRules:
    def __init__(self, read: Callable[[int, int], int | None], wrong_state: int) -> None:
        self._read = read
        self._wrong_state = wrong_state

    def register(self, hooks: NodeHooks) -> None:
        hooks.gates.append(self.gate)

    def gate(self, key: Key, value: Value) -> None:
        if key != (SYNC_COUNTER_OVERFLOW, 0) or not isinstance(value, int):
            return
        if not self.accepts(value):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        if self._read(COMMUNICATION_CYCLE_PERIOD, 0):
            raise SdoAbort(self._wrong_state)

    def accepts(self, value: int) -> bool:
        return value in SYNC_COUNTER_OVERFLOW_VALID


@breaks(SyncCounterRules, "sync_counter_overflow_unchecked")
class SyncCounterOverflowUnchecked(SyncCounterRules):
    def accepts(self, value: int) -> bool:
        return True
