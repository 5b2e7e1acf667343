"""The CiA 305 services the device answers, asked so that nothing changes: selected by its own LSS address
(1018h), asked its identity and node-ID, given its own node-ID again (pending only, never stored), then sent
back to waiting state and identified by its address range.

Not asked, because they change the device or cannot show on a configured one: configure bit timing (a device
in automatic bit-rate detection, or one that keeps the pending rate in its memory, would boot at the rate given),
activate bit timing, store configuration, identify non-configured and fastscan (only a device without a node-ID
answers them)."""

from __future__ import annotations

import struct

from encoder_conformance.cia.cia305 import ADDRESS_PARTS, LssState
from encoder_conformance.dut.lss.lss_master import LssAddress, LssMaster
from encoder_conformance.probe.findings import Findings
from encoder_conformance.probe.link import ProbeLink

NOT_ASKED = ("configure_bit_timing", "activate_bit_timing", "store_configuration", "identify_non_configured",
             "fastscan")


def _address(findings: Findings) -> LssAddress | None:
    parts = [findings.value((0x1018, sub)) for sub in range(1, 5)]
    if any(part is None or len(part) != 4 for part in parts):
        return None
    return LssAddress(*(struct.unpack("<I", part)[0] for part in parts if part is not None))


def probe_lss(link: ProbeLink, findings: Findings, response_s: float) -> None:
    address = _address(findings)
    if address is None:
        findings.notes.append("capabilities.lss: not probed, 1018h sub 1..4 (the LSS address) could not be read")
        return
    master = LssMaster(lambda cob_id, data: link.network.send_message(cob_id, data), link.frames, response_s)
    answered: list[str] = []
    if not master.switch_selective(address):
        findings.lss = []
        return
    answered += ["switch_global", "switch_selective"]  # switch global has no answer: assumed with selective
    try:
        if all(master.inquire(part) is not None for part in ADDRESS_PARTS):
            answered.append("inquire_identity")
        if master.inquire_node_id() == link.node_id:
            answered.append("inquire_node_id")
        configured = master.configure_node_id(link.node_id)
        if configured is not None and configured.error == 0:
            answered.append("configure_node_id")
    finally:
        master.switch_global(LssState.WAITING)
    if master.identify_remote(address, address) > 0:
        answered.append("identify_remote_slave")
    findings.lss = answered
    findings.notes.append(f"capabilities.lss: {', '.join(NOT_ASKED)} not probed (they change the device or only an "
                          "unconfigured device answers them); add those the manual lists")
