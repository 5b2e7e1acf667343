"""EDS import: a cleaned EDS read with canopen.import_od, turned into profile-shaped objects."""

from __future__ import annotations

import logging
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import canopen
from canopen.objectdictionary import ODArray, ODRecord, ODVariable

from encoder_conformance.profile import datatypes
from encoder_conformance.profile.eds.ini_text import CleanedEds
from encoder_conformance.profile.eds.numbers import _ACCESS_ALIASES, parse_number
from encoder_conformance.profile.eds.repair import clean_eds
from encoder_conformance.profile.schema import is_node_id_expression

logger = logging.getLogger(__name__)

#: device type and error register: mandatory in every edition of DS 301 / CiA 301 (1018h became mandatory
#: later, and legacy devices such as the POSITAL AWC 58 lack it)
MANDATORY_OBJECTS = (0x1000, 0x1001)


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

    @property
    def dummy_usage(self) -> list[int]:
        """[DummyUsage] DummyNNNN = 1: the data-type indices the device accepts as dummy mapping entries."""
        usage = self.cleaned.sections.get("DummyUsage", {})
        return [i for i in range(1, 8) if parse_number(usage.get(f"Dummy{i:04d}", "")) == 1]


def _import_cleaned(cleaned: CleanedEds) -> canopen.ObjectDictionary:
    with tempfile.TemporaryDirectory(prefix="eds-") as tmp:
        clean_path = Path(tmp) / "cleaned.eds"
        clean_path.write_text(cleaned.text, encoding="utf-8")
        with clean_path.open(encoding="utf-8") as fp:
            canopen_eds_log = logging.getLogger("canopen.objectdictionary.eds")
            level = canopen_eds_log.level
            canopen_eds_log.setLevel(logging.ERROR)  # its warnings (unknown data types) become our notes
            try:
                return canopen.import_od(fp)
            except Exception as exc:  # canopen raises configparser/KeyError/... on what we missed
                raise ValueError(f"canopen cannot read the cleaned EDS: {type(exc).__name__}: {exc}") from exc
            finally:
                canopen_eds_log.setLevel(level)


def read_eds(path: Path) -> EdsImport:
    """Clean and import ``path``; raises OSError or ValueError."""
    path = Path(path)
    data = path.read_bytes()
    if not data.strip():
        raise ValueError("the file is empty, not an EDS")
    if b"\x00" in data[:4096]:
        raise ValueError("the file holds binary data (NUL bytes), not an EDS (a text file in INI format, CiA 306)")
    cleaned = clean_eds(data)
    od = _import_cleaned(cleaned)
    notes: list[str] = []
    objects = _objects_from_od(od, cleaned, path.name, notes)
    missing = [f"{index:04X}h" for index in MANDATORY_OBJECTS if index not in objects]
    if missing:
        listed = "a [MandatoryObjects] section" if "MandatoryObjects" in cleaned.sections else "no [MandatoryObjects]"
        raise ValueError(f"not a usable EDS: it lacks the objects every CANopen device has ({', '.join(missing)}: "
                         f"CiA 301 mandatory objects, CiA 306 [MandatoryObjects]); the file has {listed} and "
                         f"{len(objects)} objects")
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
    section = cleaned.sections.get(_section_of(var), {})
    declared = parse_number(section.get("DataType", ""))  # canopen turns an unknown type into DOMAIN silently
    data_type = var.data_type
    assert data_type is not None  # canopen's EDS reader always sets it (from the required DataType)
    type_name = _type_name(data_type)
    unknown = data_type if type_name is None else declared
    entry: dict[str, Any] = {}
    if type_name is None or (unknown is not None and _type_name(unknown) is None):  # the first implies the second
        notes.append(f"{where}: data type 0x{unknown:04X} is not a CiA 301 basic type; read as DOMAIN (bytes "
                     "as found): set the real type")
        type_name = "DOMAIN"
    entry["type"] = type_name
    entry["access"] = _ACCESS_ALIASES.get((var.access_type or "").lower(), "ro")
    default = _convert_value(getattr(var, "default_raw", None), type_name, where, "default", notes)
    if default is not None:
        entry["default"] = default
    low = _convert_value(section.get("LowLimit"), type_name, where, "LowLimit", notes, is_default=False)
    high = _convert_value(section.get("HighLimit"), type_name, where, "HighLimit", notes, is_default=False)
    if isinstance(low, int) and isinstance(high, int) and low > high:  # limits are numbers (or None)
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


def _hex_default(raw: str, where: str, what: str, notes: list[str]) -> str | None:
    """An OCTET_STRING/DOMAIN default as hex bytes ('01 0A'): hex text as CiA 306 writes it, or a number
    some EDS files write instead (one byte per two hex digits); None (dropped, noted) otherwise."""
    try:
        data = datatypes.parse_hex_bytes(raw)
    except ValueError:
        number = parse_number(raw)
        if number is None or number < 0:
            notes.append(f"{where}: {what} {raw!r} is neither hex bytes nor a number; dropped")
            return None
        data = number.to_bytes(max(1, (number.bit_length() + 7) // 8), "big")
        notes.append(f"{where}: {what} {raw!r} read as the bytes {data.hex(' ').upper()}")
    return data.hex(" ").upper()


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
    if canonical in datatypes.HEX_STRING_TYPES:
        return _hex_default(raw, where, what, notes) if is_default else None
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


