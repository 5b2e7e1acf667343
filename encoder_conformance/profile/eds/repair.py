"""Repairing object sections of a vendor EDS (names, sub-indices, defaults, CompactSubObj) and
rendering the cleaned copy that canopen's reader accepts; every repair is reported."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

from encoder_conformance.profile.eds.ini_text import (
    CleanedEds,
    _decode,
    _fix_comments,
    _fix_dummy_usage,
    _fix_numbers,
    _IniReader,
    _note_number_rewrite,
)
from encoder_conformance.profile.eds.numbers import (
    _ACCESS_ALIASES,
    _ARRAY,
    _COMMISSIONING_NUMBERS,
    _DEVICE_INFO_NUMBERS,
    _DOMAIN,
    _ENTRY_NUMBERS,
    _KNOWN_SECTIONS,
    _LIMITS,
    _LIST_SECTIONS,
    _OBJECT_SECTION,
    _RECORD,
    _VAR,
    Sections,
    _is_integer_type,
    normalise_node_id_formula,
    parse_number,
)

logger = logging.getLogger(__name__)


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
    template: dict[str, str] = {k: main.pop(k) for k in ("DataType", "AccessType", "PDOMapping", "LowLimit",
                                                         "HighLimit") if k in main}  # fmt: skip
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
    return CleanedEds(_render(sections), sections, origins, fixes, reader.storage_locations, reader.lines,
                      reader.key_lines)


