"""A profile draft written as YAML: hex indices, ids and COB-IDs, flow-style sub-indices, the TODO notes as a
header comment (the same notes are under ``todo:``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml


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


