"""EDS (CiA 306) import and export for device profiles.

Import: vendor EDS files are first cleaned into a temporary copy (BOM and encoding, odd casing,
comments, duplicated sections and keys, missing ``[DummyUsage]`` entries, CompactSubObj arrays,
number formats), then read with ``canopen.import_od``; every repair is reported. The object
dictionary becomes profile-shaped ``objects:`` entries, or a whole profile draft with TODO notes.

Export: a profile becomes an EDS through ``od_builder.build_object_dictionary`` and canopen's
exporter, so other CANopen tools can drive the simulated twin.
"""

from __future__ import annotations

import logging
import re
import tempfile
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

import canopen
import yaml
from canopen.objectdictionary import ODArray, ODRecord, ODVariable
from canopen.objectdictionary import eds as canopen_eds

from . import datatypes
from .model import DeviceProfile, is_node_id_expression

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


# --------------------------------------------------------------------------- cleaning


@dataclass
class CleanedEds:
    """The cleaned EDS text plus what was changed to get there."""

    text: str
    sections: Sections
    origins: dict[str, str]  # cleaned section -> section of the vendor file it came from
    fixes: list[str] = field(default_factory=list)


def _decode(data: bytes, fixes: list[str]) -> str:
    """Text of the file: UTF-8 (BOM removed), UTF-16 with BOM, else Windows-1252/Latin-1."""
    if data.startswith(b"\xef\xbb\xbf"):
        fixes.append("removed the UTF-8 byte-order mark")
        return data[3:].decode("utf-8", errors="replace")
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        fixes.append("decoded UTF-16 (byte-order mark)")
        return data.decode("utf-16")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        pass
    try:
        text = data.decode("cp1252")
        fixes.append("file is not UTF-8; decoded as Windows-1252")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
        fixes.append("file is not UTF-8; decoded as Latin-1")
    return text


def _canonical_section(name: str) -> str:
    match = _OBJECT_SECTION.match(name)
    if match is None:
        return _SECTION_ALIASES.get(name.lower(), name)
    index = match.group(1).upper()
    if match.group(2):
        return f"{index}sub{int(match.group(3), 16):X}"
    if match.group(4):
        return index + match.group(4).capitalize()
    return index


def _canonical_key(key: str) -> str:
    if key.lower() in _KEY_ALIASES:
        return _KEY_ALIASES[key.lower()]
    for pattern, template in _KEY_PATTERNS:
        match = pattern.match(key)
        if match:
            return template.format(match.group(1))
    return key


def _strip_inline_comment(value: str) -> tuple[str, bool]:
    """Remove a ' ; comment' tail (as canopen's parser would) and trailing blanks."""
    stripped = re.sub(r"\s+;.*$", "", value).strip()
    return stripped, stripped != value.strip()


class _IniReader:
    """Lenient INI tokenizer: merges duplicates and normalises names, recording every change."""

    def __init__(self, fixes: list[str]) -> None:
        self.fixes = fixes
        self.sections: Sections = {}
        self.origins: dict[str, str] = {}
        self.renamed_keys: dict[str, list[str]] = {}
        self.inline_comments = 0
        self.current: str | None = None

    def read(self, text: str) -> Sections:
        for number, raw in enumerate(text.splitlines(), start=1):
            line = raw.strip()
            if not line or line.startswith((";", "#", "//")):
                continue
            header = _SECTION_HEADER.match(line)
            if header:
                self._section(header.group(1).strip())
            elif "=" in line and self.current is not None and line.partition("=")[0].strip():
                key, _, value = line.partition("=")
                self._option(key.strip(), value)
            else:
                self.fixes.append(f"line {number}: ignored {line[:40]!r} (not a section or key=value)")
        self._summarise()
        return self.sections

    def _section(self, name: str) -> None:
        canonical = _canonical_section(name)
        if canonical != name:
            self.fixes.append(f"section [{name}] renamed to [{canonical}]")
        if canonical in self.sections:
            self.fixes.append(f"section [{canonical}] appears more than once; merged (later keys win)")
        self.sections.setdefault(canonical, {})
        self.origins.setdefault(canonical, canonical)
        self.current = canonical

    def _option(self, key: str, raw_value: str) -> None:
        assert self.current is not None
        section = self.sections[self.current]
        value, had_comment = _strip_inline_comment(raw_value)
        self.inline_comments += had_comment
        canonical = _canonical_key(key)
        if canonical != key:
            self.renamed_keys.setdefault(self.current, []).append(f"{key} -> {canonical}")
        if canonical in section and section[canonical] != value:
            self.fixes.append(
                f"[{self.current}] {canonical} given twice ({section[canonical]!r}, {value!r}); kept the last"
            )
        section[canonical] = value

    def _summarise(self) -> None:
        for section, renames in self.renamed_keys.items():
            self.fixes.append(f"[{section}] key casing: {', '.join(renames)}")
        if self.inline_comments:
            self.fixes.append(f"removed {self.inline_comments} inline ';' comment(s)")


def _fix_numbers(sections: Sections, name: str, keys: tuple[str, ...], fixes: list[str]) -> None:
    """Rewrite ``keys`` (and BaudRate_x/DummyNNNN) of a section as numbers canopen reads with int(x, 0)."""
    section = sections.get(name, {})
    for key in [k for k in section if k in keys or re.fullmatch(r"BaudRate_\d+|Dummy\d{4}", k)]:
        old = section[key]
        value = parse_number(old)
        if value is None:
            fixes.append(f"[{name}] {key}={old!r} is not a number; removed")
            del section[key]
        elif not re.fullmatch(r"[+-]?0x[0-9a-f]+", old, re.I) and str(value) != old:
            _note_number_rewrite(name, key, old, value, fixes)
            section[key] = str(value)


def _note_number_rewrite(name: str, key: str, old: str, value: int, fixes: list[str]) -> None:
    if re.fullmatch(r"0\d+", old.strip()) and value >= 8:
        fixes.append(f"[{name}] {key}={old!r} read as decimal {value} (C-style octal would differ; check)")
    else:
        fixes.append(f"[{name}] {key}={old!r} rewritten as {value}")


def _fix_dummy_usage(sections: Sections, fixes: list[str]) -> None:
    """canopen reads Dummy0001..Dummy0007 without a fallback once [DummyUsage] exists."""
    usage = sections.get("DummyUsage")
    if usage is None:
        return
    _fix_numbers(sections, "DummyUsage", (), fixes)
    missing = [f"Dummy{i:04d}" for i in range(1, 8) if f"Dummy{i:04d}" not in usage]
    for key in missing:
        usage[key] = "0"
    if missing:
        fixes.append(f"[DummyUsage] added missing {', '.join(missing)} = 0")


def _fix_comments(sections: Sections, fixes: list[str]) -> None:
    comments = sections.get("Comments")
    if comments is None:
        return
    numbers = [int(k[4:]) for k in comments if re.fullmatch(r"Line\d+", k)]
    declared = parse_number(comments.get("Lines", ""))
    count = max([*numbers, declared or 0])
    missing = [n for n in range(1, count + 1) if f"Line{n}" not in comments]
    for n in missing:
        comments[f"Line{n}"] = ""
    if missing:
        fixes.append(f"[Comments] added empty {', '.join(f'Line{n}' for n in missing)} (Lines={count})")
    if declared != count:
        fixes.append(f"[Comments] Lines={comments.get('Lines')!r} but Line1..Line{count} given; fixed")
    comments["Lines"] = str(count)


# --------------------------------------------------------------------------- object sections


@dataclass
class _Object:
    index: int
    main: str | None = None
    subs: dict[int, str] = field(default_factory=dict)
    extras: list[str] = field(default_factory=list)  # xxxxName / xxxxValue / xxxxDenotation


def _group_objects(sections: Sections) -> dict[int, _Object]:
    objects: dict[int, _Object] = {}
    for name in sections:
        match = _OBJECT_SECTION.match(name)
        if match is None:
            continue
        obj = objects.setdefault(int(match.group(1), 16), _Object(int(match.group(1), 16)))
        if match.group(2):
            obj.subs[int(match.group(3), 16)] = name
        elif match.group(4):
            obj.extras.append(name)
        else:
            obj.main = name
    return objects


def _drop(sections: Sections, names: list[str]) -> None:
    for name in names:
        sections.pop(name, None)


def _object_type(section: dict[str, str]) -> int | None:
    """ObjectType as a number (missing means VAR, CiA 306); None if unreadable."""
    return parse_number(section["ObjectType"]) if "ObjectType" in section else _VAR


def _fix_objects(sections: Sections, origins: dict[str, str], fixes: list[str]) -> None:
    objects = _group_objects(sections)
    low = sorted(i for i in objects if i < 0x1000)
    if low:
        fixes.append("dropped data-type definition / dummy sections " + ", ".join(f"[{i:04X}]" for i in low))
    for index in low:
        obj = objects.pop(index)
        _drop(sections, [n for n in (obj.main, *obj.subs.values(), *obj.extras) if n])
    for obj in objects.values():
        if obj.main is None:
            names = [*obj.subs.values(), *obj.extras]
            fixes.append(f"{', '.join(f'[{n}]' for n in names)} without [{obj.index:04X}]; dropped")
            _drop(sections, names)
            continue
        _fix_object(sections, origins, obj, fixes)


def _fix_object(sections: Sections, origins: dict[str, str], obj: _Object, fixes: list[str]) -> None:
    assert obj.main is not None
    main = sections[obj.main]
    _fix_name(main, obj.main, f"Object {obj.index:04X}", fixes)
    compact = parse_number(main.pop("CompactSubObj", "")) or 0
    if "ObjectType" in main:
        _fix_numbers(sections, obj.main, ("ObjectType",), fixes)
    elif obj.subs or compact:
        main["ObjectType"] = f"0x{_RECORD:X}" if obj.subs else f"0x{_ARRAY:X}"
        fixes.append(f"[{obj.main}] has no ObjectType but sub-indices; set {main['ObjectType']}")
    kind = _object_type(main)
    if kind not in (_VAR, _DOMAIN, _ARRAY, _RECORD):
        fixes.append(f"[{obj.main}] ObjectType={main.get('ObjectType')!r} is no VAR/ARRAY/RECORD; dropped")
        _drop(sections, [obj.main, *obj.subs.values(), *obj.extras])
        return
    if kind in (_VAR, _DOMAIN):
        if obj.subs or obj.extras:
            fixes.append(f"[{obj.main}] is a VAR; dropped its sub-index sections")
            _drop(sections, [*obj.subs.values(), *obj.extras])
        if compact:
            fixes.append(f"[{obj.main}] CompactSubObj on a VAR; ignored")
        if not _fix_entry(sections, obj.main, fixes):
            del sections[obj.main]
        return
    if compact:
        _expand_compact(sections, origins, obj, compact, fixes)
    else:
        if obj.extras:
            fixes.append(f"{', '.join(f'[{n}]' for n in obj.extras)} without CompactSubObj; dropped")
            _drop(sections, obj.extras)
        _check_sub_number(main, obj, fixes)
    for sub, name in sorted(obj.subs.items()):
        _fix_name(sections[name], name, f"Sub-index {sub}", fixes)
        if not _fix_entry(sections, name, fixes):
            del sections[name]


def _fix_name(section: dict[str, str], name: str, fallback: str, fixes: list[str]) -> None:
    if not section.get("ParameterName"):
        section["ParameterName"] = fallback
        fixes.append(f"[{name}] has no ParameterName; named {fallback!r}")


def _check_sub_number(main: dict[str, str], obj: _Object, fixes: list[str]) -> None:
    declared = parse_number(main.get("SubNumber", ""))
    if "SubNumber" not in main:
        fixes.append(f"[{obj.main}] has no SubNumber; set {len(obj.subs)}")
    elif declared != len(obj.subs):
        fixes.append(
            f"[{obj.main}] SubNumber={main['SubNumber']!r} but {len(obj.subs)} sub-index sections; fixed"
        )
    main["SubNumber"] = f"0x{len(obj.subs):X}"


def _fix_entry(sections: Sections, name: str, fixes: list[str]) -> bool:
    """Normalise one VAR section; False if it cannot be used (no data type)."""
    section = sections[name]
    code = parse_number(section.get("DataType", ""))
    if code is None:
        fixes.append(f"[{name}] has no usable DataType ({section.get('DataType')!r}); dropped")
        return False
    section["DataType"] = f"0x{code:04X}"
    given = section.get("AccessType", "")
    access = _ACCESS_ALIASES.get(given.strip().lower())
    if access is None:
        fixes.append(f"[{name}] AccessType={given!r} unknown; assumed ro")
        access = "ro"
    elif access != given:
        fixes.append(f"[{name}] AccessType={given!r} read as {access!r}")
    section["AccessType"] = access
    _fix_numbers(sections, name, _ENTRY_NUMBERS + (_LIMITS if _is_integer_type(code) else ()), fixes)
    _fix_default(section, name, code, fixes)
    return True


def _fix_default(section: dict[str, str], name: str, code: int, fixes: list[str]) -> None:
    raw = section.get("DefaultValue")
    if raw is None or not _is_integer_type(code):
        return
    if not raw.strip():
        del section["DefaultValue"]
        return
    formula = normalise_node_id_formula(raw) if "$" in raw else None
    if formula is not None:
        if formula != raw:
            fixes.append(f"[{name}] DefaultValue={raw!r} written as {formula!r}")
        section["DefaultValue"] = formula
        return
    value = parse_number(raw)
    if value is None:
        fixes.append(f"[{name}] DefaultValue={raw!r} is not a number; removed")
        del section["DefaultValue"]
    elif not raw.lower().startswith("0x") and str(value) != raw:
        _note_number_rewrite(name, "DefaultValue", raw, value, fixes)
        section["DefaultValue"] = str(value)


def _expand_compact(
    sections: Sections, origins: dict[str, str], obj: _Object, count: int, fixes: list[str]
) -> None:
    """Write a CompactSubObj array out as explicit sub-index sections 0..count (CiA 306)."""
    assert obj.main is not None
    main = sections[obj.main]
    names = sections.pop(f"{obj.index:04X}Name", {})
    values = sections.pop(f"{obj.index:04X}Value", {})
    template = {k: main.pop(k) for k in ("DataType", "AccessType", "PDOMapping", "LowLimit", "HighLimit")
                if k in main}  # fmt: skip
    default = main.pop("DefaultValue", None)
    entries = {0: {"ParameterName": "Highest sub-index supported", "ObjectType": "0x7",
                   "DataType": "0x0005", "AccessType": "ro", "DefaultValue": str(count)}}  # fmt: skip
    for sub in range(1, count + 1):
        entry = {
            "ParameterName": names.get(str(sub)) or f"{main['ParameterName']} {sub}",
            "ObjectType": "0x7",
        }
        entry |= template
        value = values.get(str(sub), default)
        if value is not None:
            entry["DefaultValue"] = value
        entries[sub] = entry
    for sub, entry in entries.items():
        name = f"{obj.index:04X}sub{sub:X}"
        if name in sections:
            fixes.append(f"[{name}] given next to CompactSubObj; kept the explicit section")
            continue
        sections[name] = entry
        obj.subs[sub] = name
        origins[name] = obj.main if sub == 0 or str(sub) not in names else f"{obj.index:04X}Name"
    main["SubNumber"] = f"0x{count + 1:X}"
    extra = "".join(f" and [{n}]" for n in (f"{obj.index:04X}Name", f"{obj.index:04X}Value")
                    if n in obj.extras)  # fmt: skip
    fixes.append(f"[{obj.main}] CompactSubObj={count}{extra} expanded into sub-index sections 0..{count}")


def _check_object_lists(sections: Sections, fixes: list[str]) -> None:
    """Note objects listed in [xxxObjects] without a section (canopen ignores the lists)."""
    for name in _LIST_SECTIONS:
        for key, value in sections.get(name, {}).items():
            index = parse_number(value) if key != "SupportedObjects" else None
            if index is not None and f"{index:04X}" not in sections:
                fixes.append(f"[{name}] lists 0x{index:04X} but the file has no [{index:04X}] section")


def _render(sections: Sections) -> str:
    def order(name: str) -> tuple[int, int, int, str]:
        match = _OBJECT_SECTION.match(name)
        if match is None:
            known = _KNOWN_SECTIONS.index(name) if name in _KNOWN_SECTIONS else len(_KNOWN_SECTIONS)
            return (0, known, 0, name)
        sub = int(match.group(3), 16) + 1 if match.group(2) else 0
        return (1, int(match.group(1), 16), sub, name)

    lines: list[str] = []
    for name in sorted(sections, key=order):
        lines.append(f"[{name}]")
        lines.extend(f"{key}={value}" for key, value in sections[name].items())
        lines.append("")
    return "\n".join(lines)


def clean_eds(data: bytes) -> CleanedEds:
    """Repair the usual vendor oddities so that ``canopen.import_od`` can read the file."""
    fixes: list[str] = []
    reader = _IniReader(fixes)
    sections = reader.read(_decode(data, fixes))
    origins = reader.origins
    if "DeviceInfo" not in sections:
        sections["DeviceInfo"] = {}
        fixes.append("no [DeviceInfo] section (mandatory in CiA 306); added an empty one")
    _fix_dummy_usage(sections, fixes)
    _fix_comments(sections, fixes)
    _fix_numbers(sections, "DeviceInfo", _DEVICE_INFO_NUMBERS, fixes)
    _fix_numbers(sections, "DeviceComissioning", _COMMISSIONING_NUMBERS, fixes)
    _fix_objects(sections, origins, fixes)
    _check_object_lists(sections, fixes)
    return CleanedEds(_render(sections), sections, origins, fixes)


# --------------------------------------------------------------------------- import


@dataclass
class EdsImport:
    """An imported EDS: canopen's dictionary, the cleaned sections and the profile objects."""

    path: Path
    od: canopen.ObjectDictionary
    cleaned: CleanedEds
    objects: dict[int, dict[str, Any]]
    notes: list[str]  # values the profile schema cannot hold (dropped), per entry

    @property
    def fixes(self) -> list[str]:
        return self.cleaned.fixes

    @property
    def device_info(self) -> dict[str, str]:
        return self.cleaned.sections.get("DeviceInfo", {})


def _import_cleaned(cleaned: CleanedEds) -> canopen.ObjectDictionary:
    with tempfile.TemporaryDirectory(prefix="eds-") as tmp:
        clean_path = Path(tmp) / "cleaned.eds"
        clean_path.write_text(cleaned.text, encoding="utf-8")
        with clean_path.open(encoding="utf-8") as fp:
            try:
                return canopen.import_od(fp)
            except Exception as exc:  # canopen raises configparser/KeyError/... on what we missed
                raise ValueError(f"canopen cannot read the cleaned EDS: {type(exc).__name__}: {exc}") from exc


def read_eds(path: Path) -> EdsImport:
    """Clean and import ``path``; raises OSError or ValueError."""
    path = Path(path)
    cleaned = clean_eds(path.read_bytes())
    od = _import_cleaned(cleaned)
    notes: list[str] = []
    objects = _objects_from_od(od, cleaned, path.name, notes)
    return EdsImport(path, od, cleaned, objects, notes)


def objects_from_eds(path: Path) -> dict[int, dict[str, Any]]:
    """Object index -> profile-shaped object dict (as under ``objects:``) read from an EDS."""
    result = read_eds(path)
    for message in [*result.fixes, *result.notes]:
        logger.info("%s: %s", Path(path).name, message)
    return result.objects


def _type_name(code: int) -> str | None:
    try:
        canonical = datatypes.name_of_code(code)
    except ValueError:
        return None
    short = canonical.replace("UNSIGNED", "U").replace("INTEGER", "I")
    return short if short != canonical else canonical


def _objects_from_od(
    od: canopen.ObjectDictionary, cleaned: CleanedEds, filename: str, notes: list[str]
) -> dict[int, dict[str, Any]]:
    objects: dict[int, dict[str, Any]] = {}
    for index, obj in sorted(od.indices.items()):
        if index < 0x1000:  # DummyXXXX and data-type definitions
            continue
        manual = f"EDS {filename} [{cleaned.origins.get(f'{index:04X}', f'{index:04X}')}]"
        if isinstance(obj, ODVariable):
            objects[index] = {"name": obj.name, **_entry(obj, cleaned, notes), "manual": manual}
            continue
        subs = {sub: _sub_entry(obj, sub, cleaned, filename, notes) for sub in sorted(obj.subindices)}
        if not subs:
            notes.append(f"0x{index:04X} {obj.name!r}: record/array without sub-indices; skipped")
            continue
        kind = {"kind": "array"} if isinstance(obj, ODArray) else {}
        objects[index] = {"name": obj.name, **kind, "manual": manual, "subs": subs}
    return objects


def _sub_entry(
    obj: ODRecord | ODArray, sub: int, cleaned: CleanedEds, filename: str, notes: list[str]
) -> dict[str, Any]:
    var = obj.subindices[sub]
    section = f"{obj.index:04X}sub{sub:X}"
    manual = f"EDS {filename} [{cleaned.origins.get(section, section)}]"
    return {"name": var.name, **_entry(var, cleaned, notes), "manual": manual}


def _entry(var: ODVariable, cleaned: CleanedEds, notes: list[str]) -> dict[str, Any]:
    """type/access/default/min/max/pdo_mappable of one canopen variable."""
    where = f"0x{var.index:04X}.{var.subindex} {var.name!r}"
    type_name = _type_name(var.data_type)
    entry: dict[str, Any] = {}
    if type_name is None:
        notes.append(f"{where}: data type 0x{var.data_type:04X} not supported by the schema; read as DOMAIN")
        type_name = "DOMAIN"
    entry["type"] = type_name
    entry["access"] = _ACCESS_ALIASES.get((var.access_type or "").lower(), "ro")
    section = cleaned.sections.get(_section_of(var), {})
    default = _convert_value(getattr(var, "default_raw", None), type_name, where, "default", notes)
    if default is not None:
        entry["default"] = default
    low = _convert_value(section.get("LowLimit"), type_name, where, "LowLimit", notes, is_default=False)
    high = _convert_value(section.get("HighLimit"), type_name, where, "HighLimit", notes, is_default=False)
    if low is not None and high is not None and low > high:
        notes.append(f"{where}: LowLimit {low} > HighLimit {high}; limits dropped")
        low = high = None
    if low is not None:
        entry["min"] = low
    if high is not None:
        entry["max"] = high
    if var.pdo_mappable:
        entry["pdo_mappable"] = True
    return entry


def _section_of(var: ODVariable) -> str:
    parent = getattr(var, "parent", None)
    if isinstance(parent, ODRecord | ODArray):
        return f"{var.index:04X}sub{var.subindex:X}"
    return f"{var.index:04X}"


def _convert_value(
    raw: str | None, type_name: str, where: str, what: str, notes: list[str], is_default: bool = True
) -> int | str | None:
    """A DefaultValue/LowLimit/HighLimit text as the profile holds it (None: not representable).

    Strings stay strings (defaults only), $NODEID formulas stay formulas, numbers become ints
    (hex of a signed type as two's complement).
    """
    if raw is None or not str(raw).strip():
        return None
    raw = str(raw).strip()
    canonical = datatypes.canonical_name(type_name)
    if canonical in datatypes.STRING_TYPES:
        return raw if is_default else None
    if is_default and is_node_id_expression(raw):
        return raw
    limits = datatypes.value_range(canonical)
    value = parse_number(raw)
    if limits is None or value is None:
        notes.append(f"{where}: {what} {raw!r} ({canonical}) cannot be kept in a profile; dropped")
        return None
    if datatypes.is_signed(canonical) and value > limits[1] and raw.lower().startswith("0x"):
        value -= 1 << (8 * (datatypes.size_bytes(canonical) or 0))  # two's complement hex
    if not limits[0] <= value <= limits[1]:
        notes.append(f"{where}: {what} {raw!r} does not fit {canonical}; dropped")
        return None
    return value


# --------------------------------------------------------------------------- profile draft


def _slug(text: str) -> str:
    slug = re.sub(r"[^a-z0-9._-]+", "-", text.lower()).strip("-._")
    return slug or "eds-draft"


def _object_default(objects: dict[int, dict[str, Any]], index: int, sub: int = 0) -> Any:
    obj = objects.get(index)
    if obj is None:
        return None
    entry = obj.get("subs", {}).get(sub) if "subs" in obj else (obj if sub == 0 else None)
    return None if entry is None else entry.get("default")


def _info_number(info: dict[str, str], key: str) -> int | None:
    return parse_number(info.get(key, ""))


def _identity(result: EdsImport, todos: list[str]) -> dict[str, Any]:
    info, objects, source = result.device_info, result.objects, f"EDS {result.path.name}"
    identity: dict[str, Any] = {
        "vendor_name": info.get("VendorName") or "TODO vendor",
        "product_name": info.get("ProductName") or "TODO product",
    }
    for key, eds_key, sub in (("vendor_id", "VendorNumber", 1), ("product_code", "ProductNumber", 2)):
        in_od, in_info = _object_default(objects, 0x1018, sub), _info_number(info, eds_key)
        if isinstance(in_od, int) and in_info is not None and in_od != in_info:
            todos.append(f"identity.{key}: 1018h sub {sub} default 0x{in_od:X} != {eds_key} 0x{in_info:X}")
        value = in_od if isinstance(in_od, int) else in_info
        identity[key] = value
        if value is None:
            todos.append(f"identity.{key}: neither 1018h sub {sub} nor [DeviceInfo] {eds_key} gives it")
    revision = _object_default(objects, 0x1018, 3)
    revision = revision if isinstance(revision, int) else _info_number(info, "RevisionNumber")
    if revision:
        identity["revision"] = {"min": revision, "max": revision}
        todos.append("identity.revision: only the EDS revision is accepted; widen the range per the manual")
    device_type = _object_default(objects, 0x1000)
    identity["device_type"] = device_type if isinstance(device_type, int) else None
    if identity["device_type"] is None:
        todos.append("identity.device_type: 1000h has no default in the EDS")
    device_name = _object_default(objects, 0x1008)
    if isinstance(device_name, str):
        identity["device_name"] = device_name
    identity["manual"] = f"{source} [DeviceInfo]"
    if not info.get("VendorName") or not info.get("ProductName"):
        todos.append("identity: VendorName/ProductName missing in [DeviceInfo]")
    todos.append("identity.manual: cite the device manual (title, document number, edition)")
    return identity


def _names_matching(objects: dict[int, dict[str, Any]], pattern: str) -> bool:
    return any(
        re.search(pattern, obj["name"], re.I) for index, obj in objects.items() if 0x2000 <= index < 0x6000
    )


def _bus(result: EdsImport, lss: bool, todos: list[str]) -> dict[str, Any]:
    info, source = result.device_info, f"EDS {result.path.name} [DeviceInfo]"
    rates = sorted(
        (int(key[9:]) * 1000 for key, value in info.items()
         if re.fullmatch(r"BaudRate_\d+", key) and parse_number(value)),
        reverse=True,
    )  # fmt: skip
    if not rates:
        rates = [125000]
        todos.append("bus.bitrates: the EDS has no BaudRate_xxx=1 entries; 125 kbit/s assumed")
    commissioning = result.cleaned.sections.get("DeviceComissioning", {})
    node_id = _info_number(commissioning, "NodeID")
    if node_id is None or not 1 <= node_id <= 127:
        node_id = 1
        todos.append("bus.node_id: delivery node-ID not in the EDS; 1 assumed")
    baud = _info_number(commissioning, "Baudrate")
    bitrate = baud * 1000 if baud else (125000 if 125000 in rates else rates[0])
    if bitrate not in rates:
        rates = sorted([*rates, bitrate], reverse=True)
    if not baud:
        todos.append(f"bus.bitrate: delivery bit rate not in the EDS; {bitrate} assumed (or 'auto')")
    node_by, rate_by = (["lss"] if lss else []), (["lss"] if lss else [])
    if _names_matching(result.objects, r"node.?id|node.?number|node.?address"):
        node_by.insert(0, "sdo")
    if _names_matching(result.objects, r"baud|bit.?rate"):
        rate_by.insert(0, "sdo")
    todos.append("bus.node_id_set_by/bitrate_set_by: guessed from LSS_Supported and object names; check")
    return {
        "node_id": node_id,
        "bitrate": bitrate,
        "bitrates": rates,
        "node_id_set_by": node_by or ["other"],
        "bitrate_set_by": rate_by or ["other"],
        "manual": source,
    }


def _count(objects: dict[int, dict[str, Any]], first: int, last: int) -> int:
    return sum(1 for index in objects if first <= index <= last)


def _sub_numbers(objects: dict[int, dict[str, Any]], index: int) -> list[int]:
    return sorted(sub for sub in objects.get(index, {}).get("subs", {}) if sub != 0)


def _cam(objects: dict[int, dict[str, Any]], todos: list[str]) -> dict[str, int] | None:
    if 0x6300 not in objects:
        return None
    channels = max(len(_sub_numbers(objects, 0x6300)), 1)
    cams = _count(objects, 0x6310, 0x6317) or 8
    todos.append(
        f"capabilities.cam: {channels} channel(s), {cams} cam(s) per channel guessed from 6300h/631xh"
    )
    return {"channels": min(channels, 254), "cams_per_channel": min(cams, 8)}


def _capabilities(result: EdsImport, todos: list[str]) -> dict[str, Any]:
    objects, info = result.objects, result.device_info
    device_type = _object_default(objects, 0x1000)
    device_type = device_type if isinstance(device_type, int) else 0
    cia406 = any(0x6000 <= index <= 0x65FF for index in objects)
    lss = bool(_info_number(info, "LSS_Supported"))
    caps: dict[str, Any] = {
        "cia406": cia406,
        "encoder": cia406 or (device_type & 0xFFFF) == 406,
        "encoder_class": None,
        "multiturn": (device_type >> 16) == 2,
        "heartbeat_producer": 0x1017 in objects,
        "heartbeat_consumer_entries": len(_sub_numbers(objects, 0x1016)),
        "node_guarding": 0x100C in objects,
        "emcy": 0x1014 in objects,
        "sync_consumer": 0x1005 in objects,
        "store_subindices": _sub_numbers(objects, 0x1010),
        "restore_subindices": _sub_numbers(objects, 0x1011),
        "tpdos": _count(objects, 0x1800, 0x19FF),
        "rpdos": _count(objects, 0x1400, 0x15FF),
        "lss": list(_LSS_ASSUMED) if lss else [],
        "scaling": 0x6000 in objects and (0x6001 in objects or 0x6002 in objects),
        "preset": 0x6003 in objects,
        "speed": 0x6030 in objects,
        "work_area": 0x6400 in objects,
        "cam": _cam(objects, todos),
    }
    _capability_todos(result, caps, device_type, todos)
    return caps


def _capability_todos(result: EdsImport, caps: dict[str, Any], device_type: int, todos: list[str]) -> None:
    info = result.device_info
    for key, cap in (("NrOfTXPDO", "tpdos"), ("NrOfRXPDO", "rpdos")):
        declared = _info_number(info, key)
        if declared is not None and declared != caps[cap]:
            todos.append(f"capabilities.{cap}: {caps[cap]} objects in the EDS but {key}={declared}")
    if caps["cia406"] and device_type >> 16 not in (1, 2):
        todos.append(f"capabilities.multiturn: 1000h = 0x{device_type:08X} is not 0x0001xxxx/0x0002xxxx")
    if caps["lss"]:
        todos.append("capabilities.lss: LSS_Supported=1 only says 'LSS'; the service list is a minimal guess")
        if _sub_numbers(result.objects, 0x1018) != [1, 2, 3, 4]:
            todos.append("capabilities.lss: LSS needs 1018h sub 1..4, the EDS does not list all four")
    todos.append("capabilities.encoder_class: C1/C2/C3 is not in the EDS; set it from the manual")
    todos.append("capabilities: segmented/block SDO and tpdo_transmission_types are CiA defaults; check")


def _mark_run_time_values(objects: dict[int, dict[str, Any]], todos: list[str]) -> None:
    """Run-time values (position, speed, states, serial number) get dynamic/per_unit, not defaults."""
    marked: list[str] = []
    for index in sorted(_DYNAMIC_OBJECTS & objects.keys()):
        obj = objects[index]
        entries = [e for s, e in obj["subs"].items() if s != 0] if "subs" in obj else [obj]
        for entry in entries:
            _flag(entry, "dynamic", "value changes at run time")
        marked.append(f"{index:04X}h")
    serial = objects.get(0x1018, {}).get("subs", {}).get(4)
    if serial is not None:
        _flag(serial, "per_unit", "serial number differs per unit")
        marked.append("1018h sub 4 (per_unit)")
    if marked:
        todos.append(f"objects: marked dynamic/per_unit without a default check: {', '.join(marked)}")


def _flag(entry: dict[str, Any], flag: str, why: str) -> None:
    default = entry.pop("default", None)
    manual = entry.pop("manual", None)
    entry[flag] = True
    if default is not None:
        entry["notes"] = f"EDS default {default!r} not checked: {why}"
    if manual is not None:
        entry["manual"] = manual


def profile_draft_from_eds(path: Path, profile_id: str | None = None) -> tuple[dict[str, Any], list[str]]:
    """A complete profile draft from an EDS plus TODO notes for what the EDS does not say."""
    result = read_eds(Path(path))
    todos: list[str] = []
    objects = result.objects
    _mark_run_time_values(objects, todos)
    identity = _identity(result, todos)
    capabilities = _capabilities(result, todos)
    draft: dict[str, Any] = {
        "schema_version": 1,
        "id": profile_id or _slug(result.path.stem),
        "title": f"{identity['vendor_name']} {identity['product_name']} (draft from {result.path.name})",
        "identity": identity,
        "bus": _bus(result, bool(capabilities["lss"]), todos),
        "capabilities": capabilities,
        "timing": dict(_TIMING_PLACEHOLDERS),
        "objects": objects,
    }
    todos.append("timing: CiA-neutral placeholders (boot-up 1000 ms, SDO 100 ms); take them from the manual")
    todos.append("objects: manual references point at the EDS; cite the manual's tables instead")
    todos.extend(f"EDS repaired: {fix}" for fix in result.fixes)
    todos.extend(f"EDS value dropped: {note}" for note in result.notes)
    return draft, todos


# --------------------------------------------------------------------------- YAML output


class _HexInt(int):
    """An int written as 0x... in YAML."""


class _FlowDict(dict):
    """A mapping written in flow style ({a: 1, b: 2})."""


class _DraftDumper(yaml.SafeDumper):
    """SafeDumper without anchors/aliases."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


_DraftDumper.add_representer(
    _HexInt,
    lambda dumper, value: dumper.represent_scalar(
        "tag:yaml.org,2002:int", f"0x{int(value):08X}" if value > 0xFFFF else f"0x{int(value):X}"
    ),
)
_DraftDumper.add_representer(
    _FlowDict, lambda dumper, value: dumper.represent_mapping("tag:yaml.org,2002:map", value, flow_style=True)
)


def _wants_hex(index: int, key: str, value: object) -> bool:
    """Identity values, COB-IDs, mappings and other U32 communication values are written in hex."""
    if key not in ("default", "min", "max") or type(value) is not int or value < 0:
        return False
    return index in (0x1000, 0x1018) or value >= 0x100


def _hex_entry(index: int, entry: dict[str, Any]) -> dict[str, Any]:
    if index >= 0x2000 or entry.get("type") not in ("U32", "UNSIGNED32"):
        return dict(entry)
    return {key: _HexInt(value) if _wants_hex(index, key, value) else value for key, value in entry.items()}


def _yaml_ready(draft: dict[str, Any]) -> dict[str, Any]:
    data = dict(draft)
    identity = dict(data.get("identity", {}))
    for key in ("vendor_id", "product_code", "device_type"):
        if isinstance(identity.get(key), int):
            identity[key] = _HexInt(identity[key])
    if isinstance(identity.get("revision"), dict):
        identity["revision"] = _FlowDict({k: _HexInt(v) for k, v in identity["revision"].items()})
    data["identity"] = identity
    objects: dict[Any, Any] = {}
    for index, obj in sorted(data.get("objects", {}).items()):
        obj = _hex_entry(index, obj)
        if "subs" in obj:
            obj["subs"] = {sub: _FlowDict(_hex_entry(index, e)) for sub, e in sorted(obj["subs"].items())}
        objects[_HexInt(index)] = obj
    data["objects"] = objects
    return data


def write_profile_draft(draft: dict[str, Any], out: Path, todos: list[str] | None = None) -> None:
    """Write ``draft`` as YAML, hex indices/ids/COB-IDs, with the TODO notes as a header comment."""
    header = [
        f"# Profile draft {draft.get('id', '')!r} generated from an EDS by encoder_conformance.profile.eds.",
        "# Check every TODO against the device manual, then delete this header.",
    ]
    if todos:
        header.append("# TODO:")
        header.extend(f"#   - {' '.join(todo.split())}" for todo in todos)
    body = yaml.dump(_yaml_ready(draft), Dumper=_DraftDumper, sort_keys=False, allow_unicode=True, width=200)
    Path(out).write_text("\n".join(header) + "\n\n" + body, encoding="utf-8")


# --------------------------------------------------------------------------- export


def _od_variable(od: canopen.ObjectDictionary, index: int, sub: int) -> ODVariable:
    obj = od[index]
    return obj if isinstance(obj, ODVariable) else obj[sub]


def _only_profile_defaults(profile: DeviceProfile, od: canopen.ObjectDictionary) -> None:
    """An EDS states factory defaults: drop the twin's per-unit/run-time values from DefaultValue."""
    for index, sub, _obj, entry in profile.iter_entries():
        var = _od_variable(od, index, sub)
        if entry.default is None:
            var.default = None
            var.default_raw = None
        if isinstance(var.value, str) and var.data_type in (
            canopen.objectdictionary.OCTET_STRING,
            canopen.objectdictionary.DOMAIN,
        ):
            var.value = None  # canopen's DCF writer wants bytes here


def _limits_from_allowed(profile: DeviceProfile, od: canopen.ObjectDictionary) -> None:
    """An EDS has no value list: LowLimit/HighLimit are the ``allowed`` set's bounds where min/max are absent."""
    for index, sub, _obj, entry in profile.iter_entries():
        allowed = entry.value_set
        if not allowed:
            continue
        var = _od_variable(od, index, sub)
        if entry.min is None:
            var.min = allowed.minimum
        if entry.max is None:
            var.max = allowed.maximum


def export_eds(profile: DeviceProfile, path: Path, node_id: int | None = None) -> Path:
    """Write ``profile`` as an EDS (or a DCF with the twin's values if ``path`` ends in .dcf)."""
    from .od_builder import build_object_dictionary

    path = Path(path)
    od = build_object_dictionary(profile, node_id)
    _only_profile_defaults(profile, od)
    _limits_from_allowed(profile, od)
    info = od.device_information
    info.LSS_supported = bool(profile.capabilities.lss)
    revision = profile.identity.revision
    if revision is not None and revision.min == revision.max:
        info.revision_number = revision.min
    od.comments = f"Generated from device profile {profile.id} by encoder_conformance.\n{profile.title}"
    now = datetime.now()
    file_info = {  # a fresh dict: canopen's export_eds mutates its shared default argument
        "FileName": path.name,
        "FileVersion": 1,
        "FileRevision": 0,
        "EDSVersion": "4.0",
        "Description": profile.title,
        "CreationDate": now.strftime("%m-%d-%Y"),
        "CreationTime": now.strftime("%I:%M%p"),
        "CreatedBy": "encoder_conformance",
        "ModificationDate": now.strftime("%m-%d-%Y"),
        "ModificationTime": now.strftime("%I:%M%p"),
        "ModifiedBy": "encoder_conformance",
    }
    # canopen adds its own FileInfo defaults (EdsVersion=4.2) unless the OD carries imported ones
    setattr(od, "__edsFileInfo", dict(file_info))  # read by canopen as od.__edsFileInfo (not mangled)
    dcf = path.suffix.lower() == ".dcf"
    with path.open("w", encoding="utf-8") as fp:
        canopen_eds.export_eds(od, fp, file_info, device_commisioning=dcf)
    return path
