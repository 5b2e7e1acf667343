"""The abort code the device gives in the situations a probe can make without changing anything: an object
or sub-index that does not exist, a write to a read-only entry, data too short or too long. A code that
differs from CiA 301's is noted, never absorbed: whether it fails is the suite's verdict, not the draft's."""

from __future__ import annotations

from typing import Any

from encoder_conformance.cia.cia301 import ABORT_FOR_SITUATION
from encoder_conformance.probe.findings import Findings
from encoder_conformance.probe.link import ProbeLink, download, upload
from encoder_conformance.probe.put_back import PutBack

UNUSED_INDEX_CANDIDATES = (0x5FFF, 0x5FFE, 0x4FFF, 0x3FFF, 0x2FFF)


def probe_aborts(link: ProbeLink, put_back: PutBack, objects: dict[int, dict[str, Any]], findings: Findings) -> None:
    def read(situation: str, index: int, sub: int) -> None:
        answer = link.read(index, sub)
        findings.aborts[situation] = (ABORT_FOR_SITUATION[situation], answer, upload(index, sub, answer))

    def write(situation: str, index: int, data: bytes, changes: bool) -> None:
        answer = put_back.write(index, 0, data) if changes else link.write(index, 0, data)
        findings.aborts[situation] = (ABORT_FOR_SITUATION[situation], answer, download(index, 0, data, answer))

    unused = next((i for i in UNUSED_INDEX_CANDIDATES if i not in objects), None)
    if unused is not None:
        read("no_object", unused, 0)
    identity_subs = objects.get(0x1018, {}).get("subs", {})
    if identity_subs:
        read("no_subindex", 0x1018, max(identity_subs) + 1)
    device_type = findings.value((0x1000, 0))
    if device_type is not None:  # written with its own value: even a device that took it changed nothing
        write("write_ro", 0x1000, device_type, changes=False)
    heartbeat = findings.value((0x1017, 0))
    if heartbeat is not None and len(heartbeat) == 2 and objects.get(0x1017, {}).get("access") == "rw":
        write("length_low", 0x1017, heartbeat[:1], changes=True)
        write("length_high", 0x1017, heartbeat + b"\x00\x00", changes=True)
