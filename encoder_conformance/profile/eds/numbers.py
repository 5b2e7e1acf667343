"""Names and numbers of the EDS format (CiA 306): sections, keys, number syntax, node-id formulas."""

from __future__ import annotations

import logging
import re

import canopen

logger = logging.getLogger(__name__)

Sections = dict[str, dict[str, str]]

# --------------------------------------------------------------------------- names and numbers

_KNOWN_SECTIONS = (
    "FileInfo",
    "DeviceInfo",
    "DummyUsage",
    "Comments",
    "MandatoryObjects",
    "OptionalObjects",
    "ManufacturerObjects",
    "DeviceComissioning",  # CiA 306 spelling
    "SupportedModules",
    "DynamicChannels",
    "Tools",
)
_SECTION_ALIASES = {name.lower(): name for name in _KNOWN_SECTIONS} | {
    "devicecommissioning": "DeviceComissioning"
}
_LIST_SECTIONS = ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects")

_KNOWN_KEYS = (
    # FileInfo
    "FileName", "FileVersion", "FileRevision", "EDSVersion", "Description", "CreationTime",
    "CreationDate", "CreatedBy", "ModificationTime", "ModificationDate", "ModifiedBy",
    # DeviceInfo
    "VendorName", "VendorNumber", "ProductName", "ProductNumber", "RevisionNumber", "OrderCode",
    "SimpleBootUpMaster", "SimpleBootUpSlave", "Granularity", "DynamicChannelsSupported",
    "CompactPDO", "GroupMessaging", "NrOfRXPDO", "NrOfTXPDO", "LSS_Supported",
    # DeviceComissioning
    "NodeID", "NodeName", "Baudrate", "NetNumber", "NetworkName", "CANopenManager", "LSS_SerialNumber",
    # Comments and object lists
    "Lines", "SupportedObjects", "NrOfEntries",
    # objects
    "ParameterName", "ObjectType", "DataType", "AccessType", "DefaultValue", "PDOMapping",
    "LowLimit", "HighLimit", "SubNumber", "CompactSubObj", "ObjFlags", "StorageLocation",
    "ParameterValue", "Denotation", "UploadFile", "DownloadFile", "Factor", "Unit",
)  # fmt: skip
_KEY_ALIASES = {key.lower(): key for key in _KNOWN_KEYS}
_KEY_PATTERNS = (
    (re.compile(r"^baudrate_(\d+)$", re.I), "BaudRate_{}"),
    (re.compile(r"^dummy(\d{4})$", re.I), "Dummy{}"),
    (re.compile(r"^line(\d+)$", re.I), "Line{}"),
)
_OBJECT_SECTION = re.compile(r"^([0-9A-F]{4})(?:(SUB)([0-9A-F]{1,2})|(NAME|VALUE|DENOTATION))?$", re.I)

_DEVICE_INFO_NUMBERS = (
    "VendorNumber", "ProductNumber", "RevisionNumber", "Granularity", "NrOfRXPDO", "NrOfTXPDO",
    "SimpleBootUpMaster", "SimpleBootUpSlave", "DynamicChannelsSupported", "CompactPDO",
    "GroupMessaging", "LSS_Supported",
)  # fmt: skip
_COMMISSIONING_NUMBERS = ("NodeID", "Baudrate", "NetNumber", "CANopenManager")
_ENTRY_NUMBERS = ("PDOMapping", "ObjFlags")
_LIMITS = ("LowLimit", "HighLimit")

_ACCESS_ALIASES = {
    "ro": "ro", "wo": "wo", "rw": "rw", "rwr": "rwr", "rww": "rww", "const": "const",
    "co": "const", "c": "const", "r": "ro", "w": "wo", "read": "ro", "readonly": "ro",
    "read_only": "ro", "writeonly": "wo", "write_only": "wo", "readwrite": "rw", "read_write": "rw",
}  # fmt: skip

_VAR, _DOMAIN, _ARRAY, _RECORD = 0x7, 0x2, 0x8, 0x9
_SECTION_HEADER = re.compile(r"^\[([^\]]+)\]\s*(?:[;#].*)?$")
_BOOL_WORDS = {"true": 1, "yes": 1, "on": 1, "false": 0, "no": 0, "off": 0}
_NODEID_FORMULA = re.compile(
    r"^\$NODEID(?:\s*\+\s*(?P<a>0x[0-9a-f]+|\d+))?$|^(?P<b>0x[0-9a-f]+|\d+)\s*\+\s*\$NODEID$", re.I
)
_TIMING_PLACEHOLDERS = {
    "bootup_max_ms": 1000,
    "sdo_response_max_ms": 100,
    "nmt_settle_ms": 100,
    "store_max_ms": 1000,
}
_LSS_ASSUMED = ["switch_global", "switch_selective", "configure_node_id", "inquire_node_id"]
# CiA 406 values that change at run time: a profile draft does not check their EDS default
_DYNAMIC_OBJECTS = {0x1001, 0x6004, 0x600C, 0x6030, 0x6040, 0x6300, 0x6400, 0x6500, 0x6503, 0x6505, 0x6508}


def parse_number(text: str) -> int | None:
    """An EDS integer: 0x1A, 1Ah, decimal (leading zeros allowed), TRUE/FALSE; None otherwise."""
    value = text.strip().replace(" ", "")
    if not value:
        return None
    if value.lower() in _BOOL_WORDS:
        return _BOOL_WORDS[value.lower()]
    if re.fullmatch(r"[+-]?0x[0-9a-f]+", value, re.I):
        return int(value, 16)
    if re.fullmatch(r"[0-9a-f]+h", value, re.I):
        return int(value[:-1], 16)
    if re.fullmatch(r"[+-]?\d+", value):
        return int(value, 10)
    return None


def normalise_node_id_formula(text: str) -> str | None:
    """'$NodeId + 0x180', '0x180+$NODEID' -> '$NODEID+0x180'; None if ``text`` is no formula."""
    match = _NODEID_FORMULA.match(text.strip())
    if match is None:
        return None
    offset = match.group("a") or match.group("b") or "0"
    return f"$NODEID+0x{int(offset, 0):X}"


def _is_integer_type(code: int | None) -> bool:
    return code is not None and (
        code == canopen.objectdictionary.BOOLEAN or code in canopen.objectdictionary.INTEGER_TYPES
    )


