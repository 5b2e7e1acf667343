"""CiA 301 vocabulary: the numbers the standard defines, named once for the simulator and the tester.

Only facts of the CiA 301 text live here (NMT commands, states and where the commands lead, store/restore
signatures and objects, the pre-defined connection set's COB-IDs, COB-ID bits, SDO command specifiers, the
communication object ranges); nothing about a particular device.
"""

from __future__ import annotations

from enum import IntEnum

from canopen.sdo.base import CrcXmodem

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

#: The pre-defined connection set (CiA 301 §7.3.5): the CAN-ID of each communication object, the function code's
#: base + the node-ID for a node's own objects; NMT, SYNC and TIME are broadcasts without a node-ID.
NMT_COB_ID = 0x000  # NMT node control, master -> all nodes (CiA 301 §7.2.8.3.1)
SYNC_COB_ID = 0x080  # SYNC (1005h default)
EMCY_BASE = 0x080  # + node-id: the default EMCY COB-ID (1014h default)
TIME_COB_ID = 0x100  # TIME (1012h default)
TPDO1_BASE, TPDO2_BASE, TPDO3_BASE, TPDO4_BASE = 0x180, 0x280, 0x380, 0x480  # + node-id (1800h..1803h sub 1)
TPDO_BASES = (TPDO1_BASE, TPDO2_BASE, TPDO3_BASE, TPDO4_BASE)
RPDO1_BASE, RPDO2_BASE, RPDO3_BASE, RPDO4_BASE = 0x200, 0x300, 0x400, 0x500  # + node-id (1400h..1403h sub 1)
RPDO_BASES = (RPDO1_BASE, RPDO2_BASE, RPDO3_BASE, RPDO4_BASE)
SDO_RESPONSE_BASE = 0x580  # + node-id: default SDO server -> client
SDO_REQUEST_BASE = 0x600  # + node-id: default SDO client -> server
HEARTBEAT_BASE = 0x700  # + node-id: NMT error control (boot-up, heartbeat, node guarding)
HEARTBEAT_IDS = range(HEARTBEAT_BASE + 1, HEARTBEAT_BASE + 128)  # its CAN-IDs: node-IDs 1..127
#: the function code bases a node sends on in the pre-defined connection set (EMCY, TPDO1-4, SDO, error control)
NODE_TRANSMIT_BASES = (EMCY_BASE, *TPDO_BASES, SDO_RESPONSE_BASE, HEARTBEAT_BASE)
COB_ID_INVALID = 0x80000000  # bit 31 of a PDO/SYNC/EMCY COB-ID: the object does not exist / is not valid
COB_ID_NO_RTR = 0x40000000  # bit 30 of a TPDO COB-ID: no RTR allowed on this PDO (CiA 301 §7.5.2.37)
COB_ID_FRAME_29_BIT = 0x20000000  # bit 29 of a PDO COB-ID: 29-bit (extended) CAN-ID
CAN_ID_MASK = 0x7FF  # bits 0-10 of a COB-ID entry: the 11-bit CAN-ID (CiA 301 §7.5.2.35, §7.5.2.37, 1005h)
#: bits 0-29 of a PDO COB-ID: "shall not be changed while the PDO exists (bit 31 = 0)" (CiA 301 §7.5.2.35, §7.5.2.37)
COB_ID_FIXED_WHILE_VALID = 0x3FFFFFFF
#: CAN-IDs no configurable communication object may use (CiA 301 §7.3.5, restricted CAN-IDs table)
RESTRICTED_CAN_IDS: tuple[range, ...] = (
    range(0x000, 0x080), range(0x101, 0x181), range(0x581, 0x600), range(0x601, 0x680),
    range(0x6E0, 0x700), range(0x701, 0x780), range(0x780, 0x800),
)
SYNC_COUNTER_OVERFLOW = 0x1019  # 0: SYNC without counter; 2..240: the counter's overflow (CiA 301 §7.5.2.18)
COMMUNICATION_CYCLE_PERIOD = 0x1006  # 1019h is writable only while it is 0 (CiA 301 §7.5.2.18)
SYNC_COUNTER_OVERFLOW_VALID = frozenset({0, *range(2, 241)})  # 1 and 241..255 are reserved
#: 1005h bit 30: the device generates SYNC; refused (06090030h) by a device that cannot (CiA 301 §7.5.2, 1005h)
COB_ID_SYNC_GENERATE = 0x40000000
SYNC_COB_ID_OBJECT = 0x1005
#: EMCY objects (CiA 301 §7.2.7, §7.5.2): error register, error history, COB-ID, inhibit time (100 us units)
ERROR_REGISTER = 0x1001
ERROR_REGISTER_GENERIC = 0x01  # 1001h bit 0: set whenever any error is present
ERROR_HISTORY = 0x1003  # sub 0 the count (writing 0 clears, other values refused 06090030h), sub 1 the newest
EMCY_COB_ID = 0x1014
EMCY_INHIBIT_TIME = 0x1015
HEARTBEAT_CONSUMER = 0x1016  # sub n: bits 16-23 producer node-id, bits 0-15 time in ms


class EmcyCode(IntEnum):
    """EMCY error codes (CiA 301 §7.2.7.1 table 21) the simulator and the suites name."""

    ERROR_RESET = 0x0000  # error reset or no error
    DEVICE_HARDWARE = 0x5000  # device hardware (CANopenNode's code for a failed non-volatile memory at start-up)
    COMMUNICATION = 0x8100  # communication, generic (CANopenNode's code for a SYNC time-out)
    HEARTBEAT = 0x8130  # life guard error or heartbeat error
    SYNC_LENGTH = 0x8240  # unexpected SYNC data length


#: EMCY error code classes (CiA 301 v4.2.0 §7.2.7.1, table 21), the most specific prefix first: code -> meaning
EMCY_CODE_MEANINGS: dict[int, str] = {
    0x8110: "CAN overrun (objects lost)", 0x8120: "CAN in error passive mode", 0x8130: "life guard or heartbeat error",
    0x8140: "recovered from bus off", 0x8150: "CAN-ID collision", 0x8210: "PDO not processed due to length error",
    0x8220: "PDO length exceeded", 0x8230: "DAM MPDO not processed, destination object not available",
    0x8240: "unexpected SYNC data length", 0x8250: "RPDO time-out",
    0x0000: "error reset or no error", 0x1000: "generic error",
    0x2000: "current", 0x2100: "current, device input side", 0x2200: "current inside the device",
    0x2300: "current, device output side", 0x3000: "voltage", 0x3100: "mains voltage",
    0x3200: "voltage inside the device", 0x3300: "output voltage", 0x4000: "temperature",
    0x4100: "ambient temperature", 0x4200: "device temperature", 0x5000: "device hardware",
    0x6000: "device software", 0x6100: "internal software", 0x6200: "user software", 0x6300: "data set",
    0x7000: "additional modules", 0x8000: "monitoring", 0x8100: "communication", 0x8200: "protocol error",
    0x9000: "external error", 0xF000: "additional functions", 0xFF00: "device specific",
}


def emcy_meaning(code: int) -> str:
    """What an EMCY error code means by CiA 301's table 21 (its exact code, else its class, else its group)."""
    for key in (code, code & 0xFFF0, code & 0xFF00, code & 0xF000):
        if key in EMCY_CODE_MEANINGS:
            return EMCY_CODE_MEANINGS[key]
    return "not in CiA 301's table 21"


TPDO_COMMUNICATION = range(0x1800, 0x1A00)
TPDO_MAPPING = range(0x1A00, 0x1C00)
RPDO_COMMUNICATION = range(0x1400, 0x1600)
RPDO_MAPPING = range(0x1600, 0x1800)
#: a PDO's mapping object lies 200h above its communication object (1400h -> 1600h, 1800h -> 1A00h)
PDO_MAPPING_OFFSET = 0x200


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
#: where the state-changing commands lead (CiA 301 §7.3.2.2); the resets lead through initialisation and boot-up
NMT_COMMAND_TARGET: dict[NmtCommand, NmtState] = {
    NmtCommand.START: NmtState.OPERATIONAL,
    NmtCommand.STOP: NmtState.STOPPED,
    NmtCommand.ENTER_PRE_OPERATIONAL: NmtState.PRE_OPERATIONAL,
}
#: the command that brings a node into a state it reported by heartbeat
COMMAND_FOR_STATE: dict[int, str] = {
    NMT_COMMAND_TARGET[command]: name for name, command in NMT_COMMAND_NAMES.items() if command in NMT_COMMAND_TARGET
}


def is_restricted_can_id(can_id: int) -> bool:
    """A CAN-ID of the restricted table (CiA 301 §7.3.5): refused for PDOs, SYNC, EMCY, TIME and SDO."""
    return any(can_id in ids for ids in RESTRICTED_CAN_IDS)


def can_id_of(cob_id: int) -> int:
    """The 11-bit CAN-ID a COB-ID entry (PDO, SYNC, EMCY) names."""
    return cob_id & CAN_ID_MASK


def with_can_id(cob_id: int, can_id: int) -> int:
    """The COB-ID entry with its 11-bit CAN-ID replaced by ``can_id`` (its flag bits kept)."""
    return (cob_id & ~CAN_ID_MASK) | can_id


def cob_id_valid(cob_id: int) -> int:
    """The COB-ID entry with bit 31 cleared: the PDO (or EMCY, SYNC) becomes valid."""
    return cob_id & ~COB_ID_INVALID & 0xFFFFFFFF


#: TPDO transmission types (CiA 301 §7.5.2.37 table 72)
SYNC_ACYCLIC = 0
SYNC_CYCLIC = range(1, 241)
RESERVED_TRANSMISSION_TYPES = range(241, 252)  # reserved by CiA 301 table 72: never a device's capability
RTR_SYNCHRONOUS = 252
RTR_EVENT = 253
EVENT_MANUFACTURER = 254
EVENT_PROFILE = 255


class SdoClientCommand(IntEnum):
    """SDO client command specifiers, ccs: bits 7-5 of a request's byte 0 (CiA 301 §7.2.4.3); 7 is reserved."""

    DOWNLOAD_SEGMENT = 0
    INITIATE_DOWNLOAD = 1
    INITIATE_UPLOAD = 2
    UPLOAD_SEGMENT = 3
    ABORT = 4
    BLOCK_UPLOAD = 5
    BLOCK_DOWNLOAD = 6


class SdoServerCommand(IntEnum):
    """SDO server command specifiers, scs: bits 7-5 of a response's byte 0 (CiA 301 §7.2.4.3)."""

    UPLOAD_SEGMENT = 0
    DOWNLOAD_SEGMENT = 1
    INITIATE_UPLOAD = 2
    INITIATE_DOWNLOAD = 3
    ABORT = 4
    BLOCK_DOWNLOAD = 5
    BLOCK_UPLOAD = 6


#: byte 0 of an abort transfer frame, from either side (cs 4, the other bits 0: CiA 301 §7.2.4.3.17)
SDO_ABORT = 0x80
#: the client command -> the server command of its answer (an abort aside): download segment -> download segment
#: response, initiate download -> its response, initiate upload -> its response, upload segment -> upload segment
#: response, block upload / block download -> theirs
SDO_ANSWER: dict[int, int] = {
    SdoClientCommand.DOWNLOAD_SEGMENT: SdoServerCommand.DOWNLOAD_SEGMENT,
    SdoClientCommand.INITIATE_DOWNLOAD: SdoServerCommand.INITIATE_DOWNLOAD,
    SdoClientCommand.INITIATE_UPLOAD: SdoServerCommand.INITIATE_UPLOAD,
    SdoClientCommand.UPLOAD_SEGMENT: SdoServerCommand.UPLOAD_SEGMENT,
    SdoClientCommand.BLOCK_UPLOAD: SdoServerCommand.BLOCK_UPLOAD,
    SdoClientCommand.BLOCK_DOWNLOAD: SdoServerCommand.BLOCK_DOWNLOAD,
}


class SdoAbortCode(IntEnum):
    """SDO abort codes (CiA 301 §7.2.4.3.17 table 22) that the simulator and the suites name."""

    TOGGLE_BIT = 0x05030000
    TIMEOUT = 0x05040000
    COMMAND_SPECIFIER = 0x05040001
    BLOCK_SIZE = 0x05040002  # invalid block size (block mode only)
    SEQUENCE_NUMBER = 0x05040003  # invalid sequence number (block mode only)
    CRC_ERROR = 0x05040004  # CRC error (block mode only)
    UNSUPPORTED_ACCESS = 0x06010000
    READ_WO = 0x06010001
    WRITE_RO = 0x06010002
    NO_OBJECT = 0x06020000
    NOT_MAPPABLE = 0x06040041
    PDO_TOO_LONG = 0x06040042
    PARAMETER_INCOMPATIBLE = 0x06040043
    HARDWARE_ERROR = 0x06060000
    LENGTH_MISMATCH = 0x06070010
    LENGTH_HIGH = 0x06070012
    LENGTH_LOW = 0x06070013
    NO_SUBINDEX = 0x06090011
    VALUE_INVALID = 0x06090030
    VALUE_HIGH = 0x06090031
    VALUE_LOW = 0x06090032
    MAX_BELOW_MIN = 0x06090036
    GENERAL_ERROR = 0x08000000
    CANNOT_STORE = 0x08000020
    LOCAL_CONTROL = 0x08000021
    WRONG_STATE = 0x08000022
    NO_DATA = 0x08000024  # no data available (e.g. an empty entry of the error history 1003h)


def block_crc(data: bytes) -> int:
    """CRC of an SDO block transfer (CiA 301 §7.2.4.3.16: CRC-16-CCITT, x^16 + x^12 + x^5 + 1, start 0):
    canopen's own ``CrcXmodem``, the one its block client uses."""
    crc = CrcXmodem()
    crc.process(data)
    return int(crc.final())


#: CiA 301's abort code per situation, as the ``abort_code`` quirk effect names the situations
ABORT_FOR_SITUATION: dict[str, int] = {
    "write_ro": SdoAbortCode.WRITE_RO,
    "read_wo": SdoAbortCode.READ_WO,
    "no_object": SdoAbortCode.NO_OBJECT,
    "no_subindex": SdoAbortCode.NO_SUBINDEX,
    "length_high": SdoAbortCode.LENGTH_HIGH,
    "length_low": SdoAbortCode.LENGTH_LOW,
    "value_high": SdoAbortCode.VALUE_HIGH,
    "value_low": SdoAbortCode.VALUE_LOW,
    "wrong_state": SdoAbortCode.WRONG_STATE,
    "store_signature": SdoAbortCode.CANNOT_STORE,
}


#: a PDO carries at most 64 bits of mapped data (CiA 301 §7.5.2.36, §7.5.2.38: more aborts 06040042h)
PDO_MAX_BITS = 64
#: the data-type indices a mapping entry may name as a dummy (CiA 301 §7.4.7.1, EDS [DummyUsage] Dummy0001..0007)
DUMMY_INDICES = range(0x0001, 0x0008)
#: size in bits of each dummy data type (BOOLEAN, INTEGER8/16/32, UNSIGNED8/16/32)
DUMMY_BITS = {0x0001: 1, 0x0002: 8, 0x0003: 16, 0x0004: 32, 0x0005: 8, 0x0006: 16, 0x0007: 32}


def mapping_word(index: int, sub: int, bits: int) -> int:
    """A PDO mapping entry (CiA 301 §7.5.2.36, §7.5.2.38): index (16 bit), sub-index (8 bit), length in bits (8)."""
    return (index & 0xFFFF) << 16 | (sub & 0xFF) << 8 | bits & 0xFF


def mapping_fields(word: int) -> tuple[int, int, int]:
    """(index, sub-index, length in bits) of a PDO mapping entry."""
    return word >> 16 & 0xFFFF, word >> 8 & 0xFF, word & 0xFF


def pdo_mapping_of(communication_index: int) -> int | None:
    """The mapping object of a PDO communication object (1800h -> 1A00h, 1400h -> 1600h)."""
    if communication_index in TPDO_COMMUNICATION or communication_index in RPDO_COMMUNICATION:
        return communication_index + PDO_MAPPING_OFFSET
    return None
