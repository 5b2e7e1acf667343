"""What the device contradicts in its EDS, as warnings naming CiA 306 and the EDS section (with the frames seen):
a data type of another size, read access the device refuses as to a write-only entry, objects it does not have."""

from __future__ import annotations

import re
from typing import Any

from encoder_conformance.profile.eds.consistency import WARNING

DATA_TYPE = "CiA 306 v1.3.0, object descriptions: DataType"
ACCESS_TYPE = "CiA 306 v1.3.0, object descriptions: AccessType"
OBJECT_LISTS = "CiA 306 v1.3.0, object lists ([MandatoryObjects], [OptionalObjects], [ManufacturerObjects])"


def eds_section(entry: dict[str, Any]) -> str:
    """'EDS x.eds [6501sub3]' from a drafted entry's manual reference (the EDS where it has none)."""
    found = re.match(r"(EDS .*\[[^\]]+\])", str(entry.get("manual", "")))
    return found.group(1) if found else "the EDS"


def size_contradicted(entry: dict[str, Any], size: int, sent: int, frame: str) -> str:
    return (f"{WARNING}{eds_section(entry)}: DataType {entry.get('type')} is {size} bytes, the device sends {sent} "
            f"({frame}; {DATA_TYPE})")


def access_contradicted(entry: dict[str, Any], frame: str) -> str:
    return (f"{WARNING}{eds_section(entry)}: AccessType {entry.get('access')} gives read access, the device refuses "
            f"reads as of a write-only entry ({frame}; {ACCESS_TYPE})")


def objects_missing(found: list[tuple[str, dict[str, Any], str]]) -> str:
    """One warning for the objects (or sub-indices) the EDS lists and the device lacks: (name, entry, frame)."""
    listed = "; ".join(f"{name} at {eds_section(entry)} ({frame})" for name, entry, frame in found)
    return (f"{WARNING}the EDS describes {len(found)} object(s) or sub-index(es) the device does not have: {listed} "
            f"({OBJECT_LISTS}); removed from the draft (if the device should have them, that is the firmware's "
            "fault)")
