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


def persistence_label(location: str, store_subs: set[int]) -> str | None:
    """persisted_by for a writable value stored at ``location`` (None: the name says nothing we know)."""
    name = location.upper()
    if name == "RAM":
        return "volatile"
    if name == "ROM":
        return "none"
    if name.endswith("_AUTO"):
        return "auto"
    if name in GROUPS:
        sub, label = GROUPS[name]
        if sub in store_subs:
            return label
        return "store_all" if 1 in store_subs else None
    return None


def apply_storage_locations(objects: dict[int, dict[str, Any]], locations: dict[str, str], store_subs: set[int],
                            todos: list[str]) -> set[int]:
    """Label the writable values of objects whose section names a storage location; the indexes labelled."""
    labelled: set[int] = set()
    unknown: dict[str, list[int]] = {}
    for section, location in locations.items():
        if not re.fullmatch(r"[0-9A-F]{4}", section) or int(section, 16) not in objects:
            continue
        index = int(section, 16)
        label = persistence_label(location, store_subs)
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
    for location, indexes in sorted(unknown.items()):
        todos.append(f"objects.persisted_by: ;StorageLocation={location} ({', '.join(f'{i:04X}h' for i in indexes)})"
                     " is the firmware's own group: which 1010h sub stores it, or is it stored on write?")
    return labelled
