"""CiA 305 (layer setting services, LSS): the numbers, defined once for the master, the twin and the suites.

Frames are 8 bytes; byte 0 is the command specifier (cs). Master -> slave on 7E5h, slave -> master on
7E4h. Names follow CiA 305 v3 (the older "switch mode" names are the same services).
"""

from __future__ import annotations

from enum import IntEnum

MASTER_COB_ID = 0x7E5  # LSS master -> slaves
SLAVE_COB_ID = 0x7E4  # LSS slave -> master

UNCONFIGURED_NODE_ID = 0xFF  # node-ID 255: the device waits to be given one by LSS
MAX_NODE_ID = 127


class LssCommand(IntEnum):
    """Command specifiers (byte 0)."""

    SWITCH_STATE_GLOBAL = 0x04
    CONFIGURE_NODE_ID = 0x11
    CONFIGURE_BIT_TIMING = 0x13
    ACTIVATE_BIT_TIMING = 0x15
    STORE_CONFIGURATION = 0x17
    SWITCH_SELECTIVE_VENDOR = 0x40
    SWITCH_SELECTIVE_PRODUCT = 0x41
    SWITCH_SELECTIVE_REVISION = 0x42
    SWITCH_SELECTIVE_SERIAL = 0x43
    SWITCH_SELECTIVE_RESPONSE = 0x44
    IDENTIFY_VENDOR = 0x46
    IDENTIFY_PRODUCT = 0x47
    IDENTIFY_REVISION_LOW = 0x48
    IDENTIFY_REVISION_HIGH = 0x49
    IDENTIFY_SERIAL_LOW = 0x4A
    IDENTIFY_SERIAL_HIGH = 0x4B
    IDENTIFY_NON_CONFIGURED = 0x4C
    IDENTIFY_SLAVE = 0x4F  # slave's answer to identify and fastscan
    IDENTIFY_NON_CONFIGURED_SLAVE = 0x50
    FASTSCAN = 0x51
    INQUIRE_VENDOR = 0x5A
    INQUIRE_PRODUCT = 0x5B
    INQUIRE_REVISION = 0x5C
    INQUIRE_SERIAL = 0x5D
    INQUIRE_NODE_ID = 0x5E


class LssState(IntEnum):
    """The LSS state a slave is in (switch state global, byte 1)."""

    WAITING = 0
    CONFIGURATION = 1


#: the four parts of the LSS address (1018h sub 1..4), in fastscan order (LSSSub 0..3)
ADDRESS_PARTS = ("vendor", "product", "revision", "serial")
SELECTIVE_COMMANDS = (LssCommand.SWITCH_SELECTIVE_VENDOR, LssCommand.SWITCH_SELECTIVE_PRODUCT,
                      LssCommand.SWITCH_SELECTIVE_REVISION, LssCommand.SWITCH_SELECTIVE_SERIAL)
INQUIRE_COMMANDS = (LssCommand.INQUIRE_VENDOR, LssCommand.INQUIRE_PRODUCT, LssCommand.INQUIRE_REVISION,
                    LssCommand.INQUIRE_SERIAL)
IDENTIFY_RANGE_COMMANDS = (LssCommand.IDENTIFY_VENDOR, LssCommand.IDENTIFY_PRODUCT,
                           LssCommand.IDENTIFY_REVISION_LOW, LssCommand.IDENTIFY_REVISION_HIGH,
                           LssCommand.IDENTIFY_SERIAL_LOW, LssCommand.IDENTIFY_SERIAL_HIGH)

#: the command specifier of the slave's answer to a master request, where it is not the request's own (switch state
#: selective, the identify services and fastscan); switch state global draws none
ANSWERED_BY: dict[int, int | None] = {
    LssCommand.SWITCH_STATE_GLOBAL: None,
    **{command: LssCommand.SWITCH_SELECTIVE_RESPONSE for command in SELECTIVE_COMMANDS},
    **{command: LssCommand.IDENTIFY_SLAVE for command in (*IDENTIFY_RANGE_COMMANDS, LssCommand.FASTSCAN)},
    LssCommand.IDENTIFY_NON_CONFIGURED: LssCommand.IDENTIFY_NON_CONFIGURED_SLAVE,
}


def answer_command(request: int) -> int | None:
    """The command specifier a slave answers the master request ``request`` with (None: no answer)."""
    return ANSWERED_BY.get(request, request)


FASTSCAN_RESET_BIT = 0x80  # BitChecked 80h: every non-configured slave restarts its scan (LSSPos 0)

#: error codes of configure node-ID / bit timing / store configuration (byte 1 of the answer)
ERROR_NONE = 0
ERROR_OUT_OF_RANGE = 1  # node-ID 0 or 128..254, a bit-timing index the device does not have
ERROR_STORE_NOT_SUPPORTED = 1
ERROR_STORE_ACCESS = 2
ERROR_MANUFACTURER = 0xFF  # byte 2 then holds the manufacturer's code

#: CiA 305 table 0 (the standard bit-timing table): index -> bit rate in bit/s (index 5 is reserved)
BIT_TIMING_TABLE_0: dict[int, int] = {0: 1_000_000, 1: 800_000, 2: 500_000, 3: 250_000, 4: 125_000,
                                      6: 50_000, 7: 20_000, 8: 10_000}
AUTO_BIT_RATE_INDEX = 9  # automatic bit-rate detection

#: Where each LSS rule comes from, as a vendor looks it up: CiA 305 v3.0.0 "Layer setting services (LSS) and
#: protocols", by the heading of its service or protocol (its section numbers were not at hand to be cited)
CIA305 = "CiA 305 v3.0.0 (layer setting services and protocols)"
CLAUSE_FSA = "CiA 305 v3.0.0, LSS FSA (services per LSS state)"
CLAUSE_SWITCH_GLOBAL = "CiA 305 v3.0.0, switch state global service and protocol"
CLAUSE_SWITCH_SELECTIVE = "CiA 305 v3.0.0, switch state selective service and protocol"
CLAUSE_CONFIGURE_NODE_ID = "CiA 305 v3.0.0, configure node-ID service and protocol"
CLAUSE_CONFIGURE_BIT_TIMING = "CiA 305 v3.0.0, configure bit timing parameters (table 0)"
CLAUSE_ACTIVATE_BIT_TIMING = "CiA 305 v3.0.0, activate bit timing parameters service and protocol"
CLAUSE_STORE = "CiA 305 v3.0.0, store configuration service and protocol"
CLAUSE_INQUIRE = "CiA 305 v3.0.0, inquire LSS address and inquire node-ID services"
CLAUSE_IDENTIFY = "CiA 305 v3.0.0, LSS identify remote slave and identify non-configured remote slave services"
CLAUSE_FASTSCAN = "CiA 305 v3.0.0, LSS fastscan service and protocol"
