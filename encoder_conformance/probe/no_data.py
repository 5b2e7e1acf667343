"""Entries present without data: an upload answered 08000024h (no data available), e.g. an ARRAY element above the
count its sub 0 gives (CANopenNode's empty 1003h entries, a stack built from an EDS without a sub 0 DefaultValue).

They are recorded ``no_data: true``, never readable: no test reads or writes them. Where their object's sub 0 is
read-only and the EDS gives it no default, the count the device reads is taken as its default. The error history
(1003h) stays as it is: its entries fill as errors come, and the suites allow 08000024h there. A run-time value
(marked dynamic) that holds no data is no_data too: sub 0 counts 0 elements in it.
"""

from __future__ import annotations

from typing import Any

from encoder_conformance.cia.cia301 import ERROR_HISTORY, SdoAbortCode
from encoder_conformance.probe.findings import Findings, Key
from encoder_conformance.probe.link import Answer, upload

NO_DATA_CLAUSE = "CiA 301 v4.2.0 §7.2.4.3.17 table 22: 08000024h no data available"


def holds_no_data(key: Key, first: Answer) -> bool:
    """The first read answered 08000024h, outside the error history (whose entries fill as errors come)."""
    return first.abort == SdoAbortCode.NO_DATA and key[0] != ERROR_HISTORY


def _span(subs: list[int]) -> str:
    return ", ".join(map(str, subs)) if len(subs) < 4 else f"{subs[0]}..{subs[-1]}"


def _count_from_sub0(obj: dict[str, Any], index: int, findings: Findings) -> str:
    """Sub 0's value taken as its default where the EDS gives none (read-only only): the text saying so, or ''."""
    count = obj.get("subs", {}).get(0)
    data = findings.value((index, 0))
    if count is None or "default" in count or count.get("access") not in ("ro", "const") or not data:
        return ""
    count["default"] = int.from_bytes(data, "little")
    frame = upload(index, 0, findings.readings[index, 0][0])
    return f"; sub 0 has no default in the EDS and the device counts {count['default']} ({frame}): taken as its default"


def record_no_data(objects: dict[int, dict[str, Any]], findings: Findings, keys: list[Key], todos: list[str]) -> None:
    """Mark each of ``keys`` no_data (its default kept in the notes) and say so per object, with the frames."""
    by_index: dict[int, list[int]] = {}
    for index, sub in keys:
        by_index.setdefault(index, []).append(sub)
    for index, subs in sorted(by_index.items()):
        obj = objects[index]
        frames = []
        for sub in subs:
            entry = obj["subs"][sub] if "subs" in obj else obj
            default = entry.pop("default", None)
            entry["no_data"] = True
            frame = upload(index, sub, findings.readings[index, sub][0])
            frames.append(frame)
            if default is not None:
                entry["notes"] = f"EDS default {default!r} not held: the device has no data ({frame})"
        shown = "; ".join(frames[:3]) + (f"; and {len(frames) - 3} more" if len(frames) > 3 else "")
        todos.append(f"probe: {index:04X}h sub {_span(subs)}: present without data ({shown}; {NO_DATA_CLAUSE}): "
                     f"recorded no_data, never read or written by a test{_count_from_sub0(obj, index, findings)}")
