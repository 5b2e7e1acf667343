"""Quirks that refuse a write in the current situation: ``writes_preop_only`` (outside
pre-operational) and ``writes_need_scaling_bit`` (unless 6000h bit 2 is set)."""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.profile.quirk_effects import WritesNeedScalingBit, WritesPreopOnly
from encoder_conformance.sim.engine.faults import FaultSet, assemble, breaks
from encoder_conformance.sim.engine.hooks import NodeHooks
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.sdo_server import SdoAbort

SCALING_BIT = 0x04  # 6000h bit 2 (CiA 406)


class ObjectWriteGate:
    """A behaviour: writes to the listed objects are refused while ``allowed()`` is false."""

    def __init__(self, params: WritesPreopOnly | WritesNeedScalingBit, allowed: Callable[[], bool],
                 default_abort: int) -> None:
        self._objects = params.indices
        self._abort = default_abort if params.abort_code is None else params.abort_code
        self._allowed = allowed

    def register(self, hooks: NodeHooks) -> None:
        hooks.gates.append(self.gate)

    def gate(self, key: Key, value: object) -> None:
        if self.covers(*key) and not self._allowed():
            raise SdoAbort(self._abort)

    def covers(self, index: int, sub: int) -> bool:
        return index in self._objects


class PreopOnlyGate(ObjectWriteGate):
    """``writes_preop_only``: the listed objects and entries are writable in pre-operational only."""

    def __init__(self, params: WritesPreopOnly, allowed: Callable[[], bool], default_abort: int) -> None:
        super().__init__(params, allowed, default_abort)
        self._params = params

    def covers(self, index: int, sub: int) -> bool:
        return self._params.covers(index, sub)


def preop_only(params: WritesPreopOnly, state: Callable[[], NmtState | None], default_abort: int,
               faults: FaultSet | None = None) -> ObjectWriteGate:
    gate = assemble(PreopOnlyGate, faults or FaultSet())
    return gate(params, lambda: state() is NmtState.PRE_OPERATIONAL, default_abort)


def scaling_bit_needed(params: WritesNeedScalingBit, read: Callable[[int, int], int | None],
                       default_abort: int) -> ObjectWriteGate:
    return ObjectWriteGate(params, lambda: bool((read(0x6000, 0) or 0) & SCALING_BIT), default_abort)


@breaks(PreopOnlyGate, "preop_only_writes_accepted")
class PreopOnlyIgnored(PreopOnlyGate):
    def gate(self, key: Key, value: object) -> None:
        return
