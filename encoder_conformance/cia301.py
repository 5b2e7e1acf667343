"""CiA 301 vocabulary: the numbers the standard defines, named once for the simulator and the tester.

Only facts of the CiA 301 text live here (NMT commands and states, store/restore signatures and
objects, COB-ID bits, the communication object ranges); nothing about a particular device.
"""

from __future__ import annotations

from enum import IntEnum

#: 1010h 'save' and 1011h 'load' signatures as U32 (CiA 301 §7.5.2.13, §7.5.2.14): ASCII, little-endian
SAVE_SIGNATURE = 0x65766173
LOAD_SIGNATURE = 0x64616F6C
SAVE = SAVE_SIGNATURE.to_bytes(4, "little")
LOAD = LOAD_SIGNATURE.to_bytes(4, "little")

STORE_PARAMETERS = 0x1010
RESTORE_DEFAULT_PARAMETERS = 0x1011
#: 1010h/1011h sub-index per parameter group (CiA 301 §7.5.2.13): 1 all, 2 communication, 3 application
STORE_SUB_OF_GROUP = {"store_all": 1, "store_comm": 2, "store_app": 3, "store_manufacturer": 4}

#: the communication profile area: what NMT reset communication reloads (CiA 301 §7.3.2.2.3)
COMMUNICATION_AREA = range(0x1000, 0x2000)

COB_ID_INVALID = 0x80000000  # bit 31 of a PDO/SYNC/EMCY COB-ID: the object does not exist / is not valid
TPDO_COMMUNICATION = range(0x1800, 0x1A00)
TPDO_MAPPING = range(0x1A00, 0x1C00)
RPDO_COMMUNICATION = range(0x1400, 0x1600)
RPDO_MAPPING = range(0x1600, 0x1800)


class NmtCommand(IntEnum):
    """NMT command specifiers (CiA 301 §7.2.8.3.1)."""

    START = 0x01
    STOP = 0x02
    ENTER_PRE_OPERATIONAL = 0x80
    RESET_NODE = 0x81
    RESET_COMMUNICATION = 0x82


class NmtState(IntEnum):
    """States as the heartbeat / guarding reply reports them (CiA 301 §7.2.8.3.2)."""

    INITIALISING = 0x00
    BOOT_UP = 0x00  # the heartbeat's name for it: the boot-up message carries 00h
    STOPPED = 0x04
    OPERATIONAL = 0x05
    PRE_OPERATIONAL = 0x7F


#: the suites' names for the NMT commands
NMT_COMMAND_NAMES = {
    "start": NmtCommand.START,
    "stop": NmtCommand.STOP,
    "pre-operational": NmtCommand.ENTER_PRE_OPERATIONAL,
    "reset-node": NmtCommand.RESET_NODE,
    "reset-communication": NmtCommand.RESET_COMMUNICATION,
}
STATE_NAMES = {0x00: "boot-up", 0x04: "stopped", 0x05: "operational", 0x7F: "pre-operational"}
#: the command that brings a node into a state it reported by heartbeat
COMMAND_FOR_STATE = {
    NmtState.OPERATIONAL: "start",
    NmtState.STOPPED: "stop",
    NmtState.PRE_OPERATIONAL: "pre-operational",
}


def pdo_mapping_of(communication_index: int) -> int | None:
    """The mapping object of a PDO communication object (1800h -> 1A00h, 1400h -> 1600h)."""
    if communication_index in TPDO_COMMUNICATION or communication_index in RPDO_COMMUNICATION:
        return communication_index + 0x200
    return None
