"""The abort code the device gives in the situations a probe can make without changing anything: an object
or sub-index that does not exist, a write to a read-only entry, data too short or too long. A code that
differs from CiA 301's is noted, never absorbed: whether it fails is the suite's verdict, not the draft's."""

from __future__ import annotations

from typing import Any

from encoder_conformance.cia.cia301 import ABORT_FOR_SITUATION
from encoder_conformance.probe.findings import Findings
from encoder_conformance.probe.link import ProbeLink
from encoder_conformance.probe.put_back import PutBack

UNUSED_INDEX_CANDIDATES = (0x5FFF, 0x5FFE, 0x4FFF, 0x3FFF, 0x2FFF)


def probe_aborts(link: ProbeLink, put_back: PutBack, objects: dict[int, dict[str, Any]], findings: Findings) -> None:
    unused = next((i for i in UNUSED_INDEX_CANDIDATES if i not in objects), None)
    if unused is not None:
        findings.aborts["no_object"] = (ABORT_FOR_SITUATION["no_object"], link.read(unused, 0))
    identity_subs = objects.get(0x1018, {}).get("subs", {})
    if identity_subs:
        findings.aborts["no_subindex"] = (ABORT_FOR_SITUATION["no_subindex"], link.read(0x1018, max(identity_subs) + 1))
    device_type = findings.value((0x1000, 0))
    if device_type is not None:  # written with its own value: even a device that took it changed nothing
        findings.aborts["write_ro"] = (ABORT_FOR_SITUATION["write_ro"], link.write(0x1000, 0, device_type))
    heartbeat = findings.value((0x1017, 0))
    if heartbeat is not None and len(heartbeat) == 2 and objects.get(0x1017, {}).get("access") == "rw":
        findings.aborts["length_low"] = (ABORT_FOR_SITUATION["length_low"], put_back.write(0x1017, 0, heartbeat[:1]))
        findings.aborts["length_high"] = (ABORT_FOR_SITUATION["length_high"],
                                          put_back.write(0x1017, 0, heartbeat + b"\x00\x00"))
