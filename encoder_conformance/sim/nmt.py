"""NMT states, commands and which services each state allows (CiA 301 §7.3.2)."""

from __future__ import annotations

from enum import IntEnum


class NmtState(IntEnum):
    """Values as the heartbeat reports them."""

    INITIALISING = 0x00
    STOPPED = 0x04
    OPERATIONAL = 0x05
    PRE_OPERATIONAL = 0x7F


class NmtCommand(IntEnum):
    START = 0x01
    STOP = 0x02
    ENTER_PRE_OPERATIONAL = 0x80
    RESET_NODE = 0x81
    RESET_COMMUNICATION = 0x82


#: Target state of the state-changing commands (resets are handled by the node).
TARGET = {
    NmtCommand.START: NmtState.OPERATIONAL,
    NmtCommand.STOP: NmtState.STOPPED,
    NmtCommand.ENTER_PRE_OPERATIONAL: NmtState.PRE_OPERATIONAL,
}


def sdo_allowed(state: NmtState) -> bool:
    return state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)


def pdo_allowed(state: NmtState) -> bool:
    return state is NmtState.OPERATIONAL


def emcy_allowed(state: NmtState) -> bool:
    return state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)


def sync_allowed(state: NmtState) -> bool:
    return state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)
