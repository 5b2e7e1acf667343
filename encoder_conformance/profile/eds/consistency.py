"""The EDS's own inconsistencies (CiA 306), found without a device: each a warning naming the EDS line.

A warning is a todo of the draft that starts with ``WARNING`` ("warning: "); ``profile from-eds`` prints it as
a warning too. The live probe adds the ones only a device shows (``probe/eds_checks.py``).
"""

from __future__ import annotations

from encoder_conformance.profile.eds.ini_text import CleanedEds
from encoder_conformance.profile.eds.numbers import _ARRAY, _LIST_SECTIONS, _RECORD, parse_number

#: the start of a todo that is a warning about the EDS (or about what the device does with it)
WARNING = "warning: "
OBJECT_LISTS = "CiA 306 v1.3.0, object lists: SupportedObjects gives the number of entries that follow"
SUB0_DEFAULT = ("CiA 306 v1.3.0, object descriptions: DefaultValue; CiA 301 v4.2.0 §7.4.3, index and sub-index "
                "usage: sub-index 0 of an ARRAY or RECORD gives the number of its entries, the highest sub-index)")


def where(cleaned: CleanedEds, section: str, key: str | None = None) -> str:
    """'[6501sub0] (line 412)': a section of the vendor file and the line it (or its ``key``) is on."""
    origin = cleaned.origins.get(section, section)
    line = cleaned.key_lines.get((origin, key)) if key else None
    line = line or cleaned.lines.get(origin)
    return f"[{origin}]" + (f" line {line}" if line else "")


def _object_lists(cleaned: CleanedEds) -> list[str]:
    warnings = []
    for name in _LIST_SECTIONS:
        section = cleaned.sections.get(name)
        if section is None:
            continue
        declared = parse_number(section.get("SupportedObjects", ""))
        listed = [key for key in section if key != "SupportedObjects" and parse_number(key) is not None]
        if declared is not None and declared != len(listed):
            warnings.append(f"{WARNING}EDS {where(cleaned, name, 'SupportedObjects')}: SupportedObjects={declared} "
                            f"but {len(listed)} objects are listed ({OBJECT_LISTS}); a stack that trusts the count "
                            f"creates {min(declared, len(listed))} of them (the probe finds which)")
    return warnings


def _sub0_defaults(cleaned: CleanedEds) -> list[str]:
    """One warning for every ARRAY and RECORD whose sub 0 has no DefaultValue (the first 8 named with lines)."""
    found = []
    for name, section in cleaned.sections.items():
        if not name.endswith("sub0") or section.get("DefaultValue", "").strip():
            continue
        kind = parse_number(cleaned.sections.get(name[:-4], {}).get("ObjectType", ""))
        if kind in (_ARRAY, _RECORD):
            found.append(f"{'ARRAY' if kind == _ARRAY else 'RECORD'} {name[:-4]}h {where(cleaned, name)}")
    if not found:
        return []
    listed = "; ".join(found[:8]) + (f"; and {len(found) - 8} more" if len(found) > 8 else "")
    return [f"{WARNING}EDS: {len(found)} ARRAY/RECORD object(s) without a DefaultValue for sub 0 ({SUB0_DEFAULT}): "
            f"{listed}; a stack built from this EDS may hold 0 entries there and answer every element with 08000024h "
            "(no data available): probe the device (--probe)"]


def eds_warnings(cleaned: CleanedEds) -> list[str]:
    """The EDS's inconsistencies: object list counts, ARRAY/RECORD without a sub 0 default."""
    return [*_object_lists(cleaned), *_sub0_defaults(cleaned)]
