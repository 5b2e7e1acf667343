"""Storage groups from the ``;StorageLocation=`` comments EDS generators write (CANopenEditor, as used with
CANopenNode): to an INI reader a comment, to the device the group an object is stored with.

``RAM`` is lost at reset (volatile); ``ROM`` is constant; ``PERSIST_COMM`` / ``PERSIST_APP`` /
``PERSIST_MFR`` are stored by 1010h sub 2 / 3 / 4 (CiA 301 §7.5.2.13's groups; sub 1 where the device offers no
group sub); a location ending in ``_AUTO`` is written to memory by the device itself on every write
(CANopenNode's automatic storage). Any other name is the firmware's own group: the draft says so in a todo.
"""

from __future__ import annotations

import re
from typing import Any

#: location -> (the 1010h sub that stores it, its persisted_by label)
GROUPS = {"PERSIST_COMM": (2, "store_comm"), "PERSIST_APP": (3, "store_app"), "PERSIST_MFR": (4, "store_manufacturer"),
          "PERSIST_MANUFACTURER": (4, "store_manufacturer")}


def persistence_label(location: str, store_subs: set[int], named_sub: int | None = None) -> str | None:
    """persisted_by for a writable value stored at ``location`` (None: the name says nothing we know).
    ``named_sub``: a 1010h sub-index whose name names the location (CANopenNode's "Save PERSIST_APP parameters"
    is sub 5, not CiA's application sub 3): where it is not the group's CiA sub, sub 1 (all) stores it."""
    name = location.upper()
    if name == "RAM":
        return "volatile"
    if name == "ROM":
        return "none"
    if name.endswith("_AUTO"):
        return "auto"
    if name in GROUPS:
        sub, label = GROUPS[name]
        if sub in store_subs and named_sub in (None, sub):
            return label
        return "store_all" if 1 in store_subs else None
    return None


def _sub_naming(objects: dict[int, dict[str, Any]], location: str) -> int | None:
    """The 1010h sub-index whose name contains ``location`` as a word (e.g. "Save PERSIST_APP parameters")."""
    word = re.compile(rf"(?<![A-Z_]){re.escape(location.upper())}(?![A-Z_])")
    for sub, entry in objects.get(0x1010, {}).get("subs", {}).items():
        if sub > 0 and word.search(str(entry.get("name", "")).upper()):
            return int(sub)
    return None


def apply_storage_locations(objects: dict[int, dict[str, Any]], locations: dict[str, str], store_subs: set[int],
                            todos: list[str]) -> set[int]:
    """Label the writable values of objects whose section names a storage location; the indexes labelled."""
    labelled: set[int] = set()
    unknown: dict[str, list[int]] = {}
    renamed: dict[str, int] = {}
    for section, location in locations.items():
        if not re.fullmatch(r"[0-9A-F]{4}", section) or int(section, 16) not in objects:
            continue
        index = int(section, 16)
        named = _sub_naming(objects, location)
        label = persistence_label(location, store_subs, named)
        if named is not None and label == "store_all" and location.upper() in GROUPS:
            renamed.setdefault(location, named)
        if label is None:
            unknown.setdefault(location, []).append(index)
            continue
        obj = objects[index]
        entries = [e for sub, e in obj["subs"].items() if sub != 0] if "subs" in obj else [obj]
        for entry in entries:
            if entry.get("access") in ("rw", "rwr", "rww") and not entry.get("dynamic"):
                entry["persisted_by"] = label
        labelled.add(index)
    if labelled:
        todos.append(f"objects.persisted_by: {len(labelled)} objects labelled from the EDS's ;StorageLocation "
                     f"comments (RAM volatile, PERSIST_COMM/APP/MFR by 1010h sub {sorted(store_subs)}, *_AUTO "
                     "stored on write); check against the firmware's storage table")
    for location, named in sorted(renamed.items()):
        todos.append(f"objects.persisted_by: 1010h sub {named} is named for {location}, not CiA 301's sub "
                     f"{GROUPS[location.upper()][0]}: its objects are labelled store_all (1010h sub 1 stores them); "
                     "check that sub 1 stores them on this device")
    for location, indexes in sorted(unknown.items()):
        todos.append(f"objects.persisted_by: ;StorageLocation={location} ({', '.join(f'{i:04X}h' for i in indexes)})"
                     " is the firmware's own group: which 1010h sub stores it, or is it stored on write?")
    return labelled
