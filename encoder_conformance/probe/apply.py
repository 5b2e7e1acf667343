"""A draft corrected by what the probe saw; each correction and each point left open becomes a todo line
(the draft's numbered ``todo:``), and the todos the probe settled are dropped."""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

from encoder_conformance.cia.cia301 import RESERVED_TRANSMISSION_TYPES, SdoAbortCode
from encoder_conformance.probe import eds_checks
from encoder_conformance.probe.entries import draft_entries
from encoder_conformance.probe.findings import Findings, Key, TpdoTypes
from encoder_conformance.probe.link import upload
from encoder_conformance.probe.no_data import holds_no_data, record_no_data
from encoder_conformance.profile.datatypes import canonical_name, size_bytes, string_bytes
from encoder_conformance.profile.eds.draft import flag_unchecked
from encoder_conformance.profile.schema import resolve_node_id_expression
from encoder_conformance.profile.value_domain import RESERVED_TYPES_CLAUSE

#: draft todos a probe settles, by their start, with what must have been seen to settle each
SETTLED: dict[str, Callable[[Findings], bool]] = {
    "bus.node_id: delivery node-ID": lambda f: True,  # the probe found the node at its node-ID
    "capabilities.lss: LSS_Supported=1 only says": lambda f: f.lss is not None,
    "capabilities: segmented/block SDO and tpdo_transmission_types": lambda f: f.block_sdo is not None
    and f.tpdo_types is not None,
    "identity.vendor_id: neither": lambda f: f.value((0x1018, 1)) is not None,
    "identity.product_code: neither": lambda f: f.value((0x1018, 2)) is not None,
    "identity.revision: neither": lambda f: f.value((0x1018, 3)) is not None,
    "identity.device_type: 1000h has no default": lambda f: f.value((0x1000, 0)) is not None,
}


def _span(values: list[int]) -> str:
    return ", ".join(map(str, values)) if len(values) < 6 else f"{values[0]}..{values[-1]}"


def _hex(data: bytes) -> str:
    return data.hex(" ").upper() if data else "(empty)"


def expected_bytes(entry: dict[str, Any], node_id: int) -> bytes | None:
    """The draft default as the device would send it (None: no default, or one the probe cannot encode)."""
    default = resolve_node_id_expression(entry.get("default"), node_id)
    kind = canonical_name(str(entry.get("type", "")))
    size = size_bytes(kind)
    if isinstance(default, int) and size:
        signed = kind.startswith("INTEGER")
        try:
            return default.to_bytes(size, "little", signed=signed)
        except OverflowError:
            return None
    if isinstance(default, str) and size is None:
        try:
            return string_bytes(kind, default)
        except ValueError:
            return None
    return None


def _remove(objects: dict[int, dict[str, Any]], key: Key) -> None:
    index, sub = key
    obj = objects.get(index)
    if obj is None:
        return
    if "subs" in obj and sub != 0:
        obj["subs"].pop(sub, None)
    else:
        objects.pop(index)


def _missing(objects: dict[int, dict[str, Any]], findings: Findings, missing: list[Key], todos: list[str]) -> None:
    """The objects and sub-indices the device lacks, named with their EDS section and frames, then removed."""
    if not missing:
        return
    found = []
    for index, sub in missing:
        obj = objects[index]
        entry = obj["subs"].get(sub, obj) if "subs" in obj and sub else obj
        found.append((f"{index:04X}h" + (f" sub {sub}" if sub else ""), entry,
                      upload(index, sub, findings.readings[index, sub][0])))
    todos.append(eds_checks.objects_missing(found))
    for key in missing:
        _remove(objects, key)


def _entries(objects: dict[int, dict[str, Any]], findings: Findings, node_id: int, todos: list[str]) -> None:
    missing: list[Key] = []
    empty: list[Key] = []
    refused: dict[str, list[str]] = {}
    for key, entry in list(draft_entries(objects)):
        reads = findings.readings.get(key)
        if not reads:
            continue
        first = reads[0]
        where = f"{key[0]:04X}h sub {key[1]}"
        frame = upload(*key, first)
        if first.abort in (SdoAbortCode.NO_OBJECT, SdoAbortCode.NO_SUBINDEX):
            missing.append(key)
            continue
        if first.silent:
            todos.append(f"probe: {where} was not answered ({frame}); check that the device has it")
            continue
        if holds_no_data(key, first):
            empty.append(key)
            continue
        if first.abort == SdoAbortCode.READ_WO:
            todos.append(eds_checks.access_contradicted(entry, frame))
            continue
        if not first.ok:
            if not (first.abort == SdoAbortCode.NO_DATA and entry.get("dynamic")):  # an empty error-history entry
                refused.setdefault(first.describe(), []).append(where)
            continue
        assert first.data is not None
        size = size_bytes(canonical_name(str(entry.get("type", ""))))
        if size is not None and len(first.data) != size:
            todos.append(eds_checks.size_contradicted(entry, size, len(first.data), frame))
        values = [r.data for r in reads if r.data is not None]
        changed_alone = len(values) >= 2 and values[0] != values[1]
        changed_at_reset = findings.reset and values[-1] != values[0]
        writable = entry.get("access") in ("rw", "rww", "rwr")
        if changed_alone or (changed_at_reset and not writable):
            if not entry.get("dynamic"):
                why = "changes by itself" if changed_alone else "changes across an NMT reset node"
                entry.pop("per_unit", None)
                flag_unchecked(entry, "dynamic", f"the probe saw it {why.removeprefix('changes ')} "
                               f"({_hex(values[0])} -> {_hex(values[-1])})")
                todos.append(f"probe: {where} {why} ({_hex(values[0])} -> {_hex(values[-1])} in {len(values)} "
                             f"uploads of {key[0]:04X}h.{key[1]:02X}): marked dynamic (no default checked)")
            continue
        if changed_at_reset:
            todos.append(f"probe: {where} was {_hex(values[0])} and {_hex(values[-1])} after a reset (uploads of "
                         f"{key[0]:04X}h.{key[1]:02X} before and after NMT reset node): an unsaved setting (put back); "
                         "check its default")
        expected = expected_bytes(entry, node_id)
        if expected is not None and not entry.get("dynamic") and not entry.get("per_unit") and expected != values[-1]:
            todos.append(f"probe: {where} reads {_hex(values[-1])} ({upload(*key, reads[-1])}), the EDS default is "
                         f"{entry.get('default')!r}: a value changed and stored by the device's owner, or the EDS and "
                         "the firmware disagree (a run fails it)")
    for answer, places in refused.items():
        todos.append(f"probe: reading {', '.join(places)} was refused with {answer} although the EDS gives read "
                     f"access (upload -> {answer})")
    record_no_data(objects, findings, empty, todos)
    _missing(objects, findings, missing, todos)


def _identity(draft: dict[str, Any], findings: Findings, todos: list[str]) -> None:
    identity = draft["identity"]

    def u32(key: Key) -> int | None:
        data = findings.value(key)
        return struct.unpack("<I", data)[0] if data is not None and len(data) == 4 else None

    for field, key in (("device_type", (0x1000, 0)), ("vendor_id", (0x1018, 1)), ("product_code", (0x1018, 2))):
        value = u32(key)
        if value is not None and identity.get(field) != value:
            todos.append(f"probe: identity.{field} {identity.get(field)!r} in the EDS, the device reports 0x{value:X}: "
                         "the device's value taken")
            identity[field] = value
    revision = u32((0x1018, 3))
    span = identity.get("revision")
    if revision is not None and (span is None or not span["min"] <= revision <= span["max"]):
        low, high = (revision, revision) if span is None else (min(span["min"], revision), max(span["max"], revision))
        identity["revision"] = {"min": low, "max": high}
        todos.append(f"probe: the device reports revision 0x{revision:X}; identity.revision widened to include it")


def _capabilities(draft: dict[str, Any], findings: Findings, todos: list[str]) -> None:
    caps, objects = draft["capabilities"], draft["objects"]
    caps["tpdos"] = sum(1 for i in objects if 0x1800 <= i <= 0x19FF)
    caps["rpdos"] = sum(1 for i in objects if 0x1400 <= i <= 0x15FF)
    consumers = findings.value((0x1016, 0))
    if consumers:
        caps["heartbeat_consumer_entries"] = consumers[0]
    for attribute in ("block_sdo", "segmented_sdo", "sync_producer", "node_guarding", "store_subindices",
                      "restore_subindices", "lss"):
        value = getattr(findings, attribute)
        if value is not None:
            caps[attribute] = value
    if findings.tpdo_types is not None:
        _tpdo_types(caps, findings.tpdo_types, todos)
    for situation, (cia_code, answer, frames) in findings.aborts.items():
        if answer.abort != cia_code:
            todos.append(f"probe: {situation.replace('_', ' ')}: the device answered {answer.describe()} ({frames}), "
                         f"CiA 301 names {cia_code:08X}h (the SDO suites judge it; declare an abort_code quirk only "
                         "where the manual documents it)")


def _tpdo_types(caps: dict[str, Any], types: TpdoTypes, todos: list[str]) -> None:
    """The types the device took, except those CiA reserves: a reserved type taken is a finding, never a capability
    (the profile keeps CiA's list, so the value-domain test fails the device on it)."""
    reserved = [t for t in types.accepted if t in RESERVED_TRANSMISSION_TYPES]
    caps["tpdo_transmission_types"] = [t for t in types.accepted if t not in RESERVED_TRANSMISSION_TYPES]
    refused = "; ".join(f"{_span(values)} ({'no answer' if code == 0 else f'{code:08X}h'}: "
                        f"{types.frames.get(values[0])})" for code, values in types.refused.items())
    todos.append(f"probe: {types.communication_index:04X}h sub 2 accepted {len(types.accepted)} transmission types "
                 f"(e.g. {types.frames.get(types.accepted[0]) if types.accepted else 'none'}); refused: "
                 f"{refused or 'none'}; the manual decides whether refusing is documented "
                 "(tpdo_transmission_types_refusal)")
    if reserved:
        shown = "; ".join(types.frames[t] for t in reserved[:3]) + ("; ..." if len(reserved) > 3 else "")
        todos.append(f"probe: DEVIATION: {types.communication_index:04X}h sub 2 accepted the transmission types "
                     f"CiA reserves: {_span(reserved)} ({shown}; {RESERVED_TYPES_CLAUSE}); not taken as a "
                     "capability: capabilities.tpdo_transmission_types keeps CiA's list, and a run fails the device "
                     "on them (test_value_domain)")


def apply_findings(draft: dict[str, Any], todos: list[str], findings: Findings, node_id: int) -> list[str]:
    """Correct ``draft`` in place; the todo list with settled items dropped and the probe's added."""
    kept = [t for t in todos if not any(t.startswith(start) and seen(findings) for start, seen in SETTLED.items())]
    draft["bus"]["node_id"] = node_id
    added: list[str] = []
    _entries(draft["objects"], findings, node_id, added)
    _identity(draft, findings, added)
    _capabilities(draft, findings, added)
    added += findings.notes
    added += [f"probe: NOT PUT BACK: {failure}" for failure in findings.put_back_failures]
    result = [" ".join(t.split()) for t in kept + added]
    draft["todo"] = result
    return result
