"""Every entry of the draft read from the device: whether it exists, how long it is, whether it changes
(between two reads, or across an NMT reset node: a value that does is not a default)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

from encoder_conformance.probe.findings import Findings, Key
from encoder_conformance.probe.link import ProbeLink
from encoder_conformance.probe.put_back import PutBack


def draft_entries(objects: dict[int, dict[str, Any]]) -> Iterator[tuple[Key, dict[str, Any]]]:
    """(index, sub) and the entry dict of every entry of a draft's objects."""
    for index, obj in sorted(objects.items()):
        if "subs" in obj:
            for sub, entry in sorted(obj["subs"].items()):
                yield (index, sub), entry
        else:
            yield (index, 0), obj


def readable(entry: dict[str, Any]) -> bool:
    return entry.get("access") != "wo" and not entry.get("no_data")


def read_all(link: ProbeLink, objects: dict[int, dict[str, Any]], findings: Findings) -> None:
    """One read of each readable entry, appended to its readings."""
    for key, entry in draft_entries(objects):
        if readable(entry):
            findings.readings.setdefault(key, []).append(link.read(*key))


def reset_and_reread(link: ProbeLink, objects: dict[int, dict[str, Any]], findings: Findings, put_back: PutBack,
                     boot_timeout_s: float) -> None:
    """NMT reset node, the boot-up waited for, every entry read again. A writable value the reset changed was
    the owner's unsaved setting: it goes into the put-back ledger."""
    mark = link.nmt_command("reset-node")
    started = time.monotonic()
    if link.boot_up(mark, boot_timeout_s) is None:
        findings.notes.append(f"probe: no boot-up message within {boot_timeout_s:.1f} s of an NMT reset node; values "
                              "that change only at a reset were not looked for")
        return
    findings.reset = True
    findings.boot_up_ms = (time.monotonic() - started) * 1000
    read_all(link, objects, findings)
    for key, entry in draft_entries(objects):
        reads = findings.readings.get(key, [])
        stable_before = len(reads) >= 3 and reads[0].data is not None and reads[0].data == reads[1].data
        if stable_before and reads[-1].data != reads[0].data and entry.get("access") in ("rw", "rww", "rwr"):
            assert reads[0].data is not None
            put_back.remember(*key, reads[0].data)
