"""Which services each NMT state allows, and where the state-changing commands lead (CiA 301 §7.3.2)."""

from __future__ import annotations

from encoder_conformance.cia.cia301 import NMT_COMMAND_TARGET, NmtCommand, NmtState

__all__ = ["TARGET", "NmtCommand", "NmtState", "emcy_allowed", "pdo_allowed", "sdo_allowed"]


#: Target state of the state-changing commands (resets are handled by the node).
TARGET = NMT_COMMAND_TARGET


def sdo_allowed(state: NmtState) -> bool:
    return state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)


def pdo_allowed(state: NmtState) -> bool:
    return state is NmtState.OPERATIONAL


def emcy_allowed(state: NmtState) -> bool:
    return state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)

