"""A profile draft from an EDS (identity, bus, capabilities, objects, TODO notes) and its YAML output."""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any

import yaml

from .importer import EdsImport, read_eds
from .numbers import _DYNAMIC_OBJECTS, _LSS_ASSUMED, _TIMING_PLACEHOLDERS, parse_number

logger = logging.getLogger(__name__)


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


