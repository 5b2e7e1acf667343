"""A profile draft from an EDS (identity, bus, capabilities, objects, TODO notes) and its YAML output."""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any

from encoder_conformance.cia.cia301 import PDO_MAPPING_OFFSET
from encoder_conformance.profile.eds.consistency import eds_warnings
from encoder_conformance.profile.eds.importer import EdsImport, read_eds
from encoder_conformance.profile.eds.numbers import _DYNAMIC_OBJECTS, _LSS_ASSUMED, _TIMING_PLACEHOLDERS, parse_number
from encoder_conformance.profile.eds.storage import apply_storage_locations

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
    identity: dict[str, Any] = {  # as the EDS has them, also empty: a placeholder would reach to-eds
        "vendor_name": info.get("VendorName", ""),
        "product_name": info.get("ProductName", ""),
    }
    if info.get("OrderCode"):
        identity["order_code"] = info["OrderCode"]
    for key, eds_key, sub in (("vendor_id", "VendorNumber", 1), ("product_code", "ProductNumber", 2),
                              ("revision", "RevisionNumber", 3)):
        value = _identity_number(objects, info, key, eds_key, sub, todos)
        if key == "revision":
            if value is not None:
                identity["revision"] = {"min": value, "max": value}
                todos.append("identity.revision: only the EDS revision is accepted; widen the range per the manual")
        else:
            identity[key] = value
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


def _identity_number(objects: dict[int, dict[str, Any]], info: dict[str, str], key: str, eds_key: str, sub: int,
                     todos: list[str]) -> int | None:
    """1018h sub ``sub`` as the profile should expect it, and the object's default set to match (the twin
    then reports it). None where 1018h has no such sub-index: the device cannot report it."""
    entry = objects.get(0x1018, {}).get("subs", {}).get(sub)
    in_info = _info_number(info, eds_key)
    if entry is None:
        if in_info:
            todos.append(f"identity.{key}: [DeviceInfo] {eds_key} = 0x{in_info:X}, but 1018h has no sub {sub}, so the "
                         "device cannot report it; not checked")
        return None
    in_od = entry.get("default")
    in_od = in_od if isinstance(in_od, int) else None
    if in_od and in_info is not None and in_od != in_info:
        todos.append(f"identity.{key}: 1018h sub {sub} default 0x{in_od:X} != {eds_key} 0x{in_info:X}; the object's "
                     "value is used")
    value = in_od or in_info  # a 0 default in 1018h is an EDS placeholder where [DeviceInfo] gives the number
    if value is None:
        todos.append(f"identity.{key}: neither 1018h sub {sub} nor [DeviceInfo] {eds_key} gives it")
        return None
    if in_od != value:
        todos.append(f"identity.{key}: 1018h sub {sub} has {'no' if in_od is None else 'a 0'} default; "
                     f"[DeviceInfo] {eds_key} 0x{value:X} taken")
    entry.pop("per_unit", None)
    entry["default"] = value
    return value


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


#: CiA device profiles by the number in 1000h bits 0..15
CIA_PROFILES = {401: "generic I/O module", 402: "drive and motion control", 404: "measuring device",
                406: "encoder", 410: "inclinometer", 0: "no standard device profile"}


def _cia_profile(objects: dict[int, dict[str, Any]], device_type: int, todos: list[str]) -> int:
    """The CiA device profile number 1000h names (bits 0..15); encoder capabilities are drafted for 406 only."""
    number = device_type & 0xFFFF
    in_range = any(0x6000 <= index <= 0x65FF for index in objects)
    if number != 406 and in_range:
        todos.append(f"capabilities.cia406: 1000h = 0x{device_type:08X} names CiA profile {number} "
                     f"({CIA_PROFILES.get(number, 'other')}), not 406, although objects 6000h..65FFh exist: drafted "
                     "as a non-encoder; if the device is an encoder, set cia406/encoder/multiturn from its manual")
    if number == 406 and device_type >> 16 not in (1, 2):
        todos.append(f"capabilities.multiturn: 1000h = 0x{device_type:08X} says neither single-turn (1) nor "
                     "multi-turn (2) in bits 16..31; set it from the manual")
    return number


def _capabilities(result: EdsImport, todos: list[str]) -> dict[str, Any]:
    objects, info = result.objects, result.device_info
    device_type = _object_default(objects, 0x1000)
    device_type = device_type if isinstance(device_type, int) else 0
    cia406 = _cia_profile(objects, device_type, todos) == 406
    lss = bool(_info_number(info, "LSS_Supported"))
    caps: dict[str, Any] = {
        "cia406": cia406,
        "encoder": cia406,
        "encoder_class": None,
        "multiturn": cia406 and (device_type >> 16) == 2,
        "heartbeat_producer": 0x1017 in objects,
        "heartbeat_consumer_entries": len(_sub_numbers(objects, 0x1016)),
        "node_guarding": 0x100C in objects,
        "emcy": 0x1014 in objects,
        "sync_consumer": 0x1005 in objects,
        "store_subindices": _sub_numbers(objects, 0x1010),
        "restore_subindices": _sub_numbers(objects, 0x1011),
        "tpdos": _count(objects, 0x1800, 0x19FF),
        "rpdos": _count(objects, 0x1400, 0x15FF),
        "pdo_granularity": _info_number(info, "Granularity"),
        "pdo_dummy_mapping": result.dummy_usage,
        "lss": list(_LSS_ASSUMED) if lss else [],
        "scaling": cia406 and 0x6000 in objects and (0x6001 in objects or 0x6002 in objects),
        "preset": cia406 and 0x6003 in objects,
        "speed": cia406 and 0x6030 in objects,
        "work_area": cia406 and 0x6400 in objects,
        "cam": _cam(objects, todos) if cia406 else None,
    }
    _capability_todos(result, caps, device_type, todos)
    return caps


def _mapping_todos(objects: dict[int, dict[str, Any]], todos: list[str]) -> None:
    """A default PDO mapping naming an object the EDS lacks (an inconsistent EDS): the draft keeps no default
    for that mapping (the twin maps nothing there, as CiA 301 §7.5.2.38 would refuse the entry) and says so."""
    for mapping in sorted(i for i in objects if 0x1600 <= i <= 0x17FF or 0x1A00 <= i <= 0x1BFF):
        subs = objects[mapping].get("subs", {})
        words = [e.get("default") for sub, e in subs.items() if sub > 0]
        missing = sorted({w >> 16 for w in words if isinstance(w, int) and w >> 16 >= 8 and w >> 16 not in objects})
        if not missing:
            continue
        for entry in subs.values():
            entry.pop("default", None)
        todos.append(f"{mapping:04X}h: the EDS maps {', '.join(f'{i:04X}h' for i in missing)}, which it does not "
                     "define; the draft gives this mapping no default (the twin maps nothing there)")


def _tpdo_todos(objects: dict[int, dict[str, Any]], todos: list[str]) -> None:
    """A TPDO without a transmission type or a mapping in the EDS: what makes it send is unknown."""
    for comm in sorted(i for i in objects if 0x1800 <= i <= 0x19FF):
        subs, mapping = objects[comm].get("subs", {}), comm + PDO_MAPPING_OFFSET
        missing = [what for what, known in (("transmission type (sub 2)", 2 in subs and "default" in subs[2]),
                                            (f"mapping ({mapping:04X}h)", mapping in objects)) if not known]
        if missing:
            todos.append(f"TPDO {comm:04X}h: the EDS gives no {' and no '.join(missing)}; the twin sends nothing "
                         "on it and the suites that need a sending TPDO skip: complete it from the manual")


def _capability_todos(result: EdsImport, caps: dict[str, Any], device_type: int, todos: list[str]) -> None:
    info = result.device_info
    for key, cap in (("NrOfTXPDO", "tpdos"), ("NrOfRXPDO", "rpdos")):
        declared = _info_number(info, key)
        if declared is not None and declared != caps[cap]:
            todos.append(f"capabilities.{cap}: {caps[cap]} objects in the EDS but {key}={declared}")
    if caps["lss"]:
        todos.append("capabilities.lss: LSS_Supported=1 only says 'LSS'; the service list is a minimal guess")
        if _sub_numbers(result.objects, 0x1018) != [1, 2, 3, 4]:
            todos.append("capabilities.lss: LSS needs 1018h sub 1..4, the EDS does not list all four")
    if caps["cia406"]:
        todos.append("capabilities.encoder_class: C1/C2/C3 is not in the EDS; set it from the manual")
    todos.append("capabilities: segmented/block SDO and tpdo_transmission_types are CiA defaults; check")


def _mark_run_time_values(objects: dict[int, dict[str, Any]], todos: list[str]) -> None:
    """Run-time values (position, speed, states, serial number) get dynamic/per_unit, not defaults."""
    marked: list[str] = []
    for index in sorted(_DYNAMIC_OBJECTS & objects.keys()):
        obj = objects[index]
        entries = [e for s, e in obj["subs"].items() if s != 0] if "subs" in obj else [obj]
        for entry in entries:
            flag_unchecked(entry, "dynamic", "value changes at run time")
        marked.append(f"{index:04X}h")
    history = objects.get(0x1003, {}).get("subs", {})
    if history:  # CiA 301 §7.5.2.4: sub 0 counts the errors (rw, writing 0 clears them), subs 1.. hold them
        count = history.get(0)
        if count is not None:
            count.update(name="Number of errors", access="rw")
        for entry in history.values():
            flag_unchecked(entry, "dynamic", "the error history changes at run time")
        marked.append("1003h (error history: sub 0 the count, rw)")
    serial = objects.get(0x1018, {}).get("subs", {}).get(4)
    if serial is not None:
        flag_unchecked(serial, "per_unit", "serial number differs per unit")
        marked.append("1018h sub 4 (per_unit)")
    if 0x650B in objects and "subs" not in objects[0x650B]:
        flag_unchecked(objects[0x650B], "per_unit", "serial number differs per unit")
        marked.append("650Bh (per_unit)")
    if marked:
        todos.append(f"objects: marked dynamic/per_unit without a default check: {', '.join(marked)}")


def flag_unchecked(entry: dict[str, Any], flag: str, why: str) -> None:
    """Mark ``entry`` dynamic or per_unit: its default is dropped (kept in the notes with ``why``)."""
    default = entry.pop("default", None)
    manual = entry.pop("manual", None)
    entry[flag] = True
    if default is not None:
        entry["notes"] = f"EDS default {default!r} not checked: {why}"
    if manual is not None:
        entry["manual"] = manual


#: 1010h sub-index -> (persisted_by label, the object range CiA 301 §7.5.2.13 gives that sub-index)
STORE_GROUP_RANGES = {2: ("store_comm", range(0x1000, 0x2000)), 3: ("store_app", range(0x6000, 0xA000)),
                      4: ("store_manufacturer", range(0x2000, 0x6000))}
NOT_STORED = {0x1010, 0x1011, 0x1003, 0x1F51}  # commands, the error history, program control


def _draft_persistence(objects: dict[int, dict[str, Any]], locations: dict[str, str], todos: list[str]) -> None:
    """persisted_by for the writable values with a default: from the EDS's ;StorageLocation comments where it
    has them, else from the sub-indices 1010h offers (CiA 301: 1 all, 2 communication 1000h..1FFFh,
    3 application 6000h..9FFFh, 4 manufacturer 2000h..5FFFh)."""
    subs = set(_sub_numbers(objects, 0x1010))
    located = apply_storage_locations(objects, locations, subs, todos)
    if not subs:
        return
    labelled = 0
    for index, obj in objects.items():
        if index in NOT_STORED or index in _DYNAMIC_OBJECTS or index in located:
            continue
        entries = [e for sub, e in obj["subs"].items() if sub != 0] if "subs" in obj else [obj]
        group = next((label for sub, (label, span) in STORE_GROUP_RANGES.items() if sub in subs and index in span),
                     "store_all" if 1 in subs else None)
        for entry in entries:
            if group and entry.get("access") in ("rw", "rwr", "rww") and "default" in entry:
                entry["persisted_by"] = group
                labelled += 1
    if labelled:
        todos.append(f"objects.persisted_by: {labelled} writable values labelled from 1010h sub {sorted(subs)} by "
                     "CiA 301's groups; check which values the device really stores (the manual's storage table)")


def profile_draft_from_eds(path: Path, profile_id: str | None = None) -> tuple[dict[str, Any], list[str]]:
    """A complete profile draft from an EDS plus TODO notes for what the EDS does not say."""
    result = read_eds(Path(path))
    todos: list[str] = eds_warnings(result.cleaned)
    objects = result.objects
    _mark_run_time_values(objects, todos)
    _draft_persistence(objects, result.cleaned.storage_locations, todos)
    identity = _identity(result, todos)
    capabilities = _capabilities(result, todos)
    _tpdo_todos(objects, todos)
    _mapping_todos(objects, todos)
    draft: dict[str, Any] = {
        "schema_version": 1,
        "id": profile_id or _slug(result.path.stem),
        "title": f"{identity['vendor_name']} {identity['product_name']}".strip() + f" (draft from {result.path.name})",
        "identity": identity,
        "bus": _bus(result, bool(capabilities["lss"]), todos),
        "capabilities": capabilities,
        "timing": dict(_TIMING_PLACEHOLDERS),
        "objects": objects,
    }
    todos.append("timing: CiA-neutral placeholders (boot-up 1000 ms, SDO 100 ms); take them from the manual")
    todos.append("objects: manual references point at the EDS; cite the manual's tables instead")
    todos.extend(f"EDS repaired: {fix}" for fix in result.fixes)
    todos.extend(f"EDS: {note}" for note in result.notes)
    draft["todo"] = [" ".join(todo.split()) for todo in todos]
    return draft, todos
