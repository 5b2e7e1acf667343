"""One probe of a live device, from connecting to putting everything back (the steps in order)."""

from __future__ import annotations

import struct
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from encoder_conformance.cia.cia301 import NmtState
from encoder_conformance.config.bus import BusConfig
from encoder_conformance.errors import DutLostError
from encoder_conformance.probe import aborts, entries, lss_services, services
from encoder_conformance.probe.apply import apply_findings
from encoder_conformance.probe.findings import Findings
from encoder_conformance.probe.link import ProbeLink
from encoder_conformance.probe.put_back import PutBack


@dataclass(frozen=True)
class ProbeOptions:
    bus: BusConfig
    node_id: int
    reset: bool = True  # one NMT reset node, to find values that change across it
    sdo_timeout_s: float = 0.5
    boot_timeout_s: float = 5.0
    lss_response_s: float = 0.05


@dataclass
class ProbeResult:
    findings: Findings
    todos: list[str]
    seconds: float
    requests: int

    @property
    def restored(self) -> bool:
        return not self.findings.put_back_failures


def _state_found(link: ProbeLink, findings: Findings) -> None:
    """The NMT state from one heartbeat, if the heartbeat is on (to leave the device in it)."""
    period = findings.value((0x1017, 0))
    if period is None or len(period) != 2 or not struct.unpack("<H", period)[0]:
        return
    beat = link.wait(link.is_error_control, 2 * struct.unpack("<H", period)[0] / 1000 + 0.1)
    findings.nmt_state_found = None if beat is None else beat.data[0] & 0x7F


def _leave_as_found(link: ProbeLink, findings: Findings) -> None:
    if not findings.reset:
        return
    if findings.nmt_state_found == NmtState.OPERATIONAL:
        link.nmt_command("start")
    elif findings.nmt_state_found is None:
        findings.notes.append("probe: the device was reset once and is in the state it boots into (its state before "
                              "was unknown: no heartbeat)")


def probe_device(draft: dict[str, Any], todos: list[str], options: ProbeOptions,
                 say: Callable[[str], None] = lambda text: None) -> ProbeResult:
    """Probe the device at ``options.node_id`` and correct ``draft`` in place. Raises DutLostError when the
    node does not answer at all (nothing was changed then)."""
    started = time.monotonic()
    objects: dict[int, dict[str, Any]] = draft["objects"]
    findings = Findings()
    link = ProbeLink(options.bus, options.node_id, options.sdo_timeout_s)
    put_back = PutBack(link)
    try:
        if link.first_answer(options.boot_timeout_s).silent:
            raise DutLostError(f"node {options.node_id} did not answer an SDO read of 1000h within "
                               f"{options.boot_timeout_s:.0f} s on {options.bus.describe()}: check the node-ID "
                               "(--node-id), the bus and the bit rate, and that the device is on")
        say(f"probe: reading {sum(1 for _ in entries.draft_entries(objects))} entries twice")
        entries.read_all(link, objects, findings)
        _state_found(link, findings)
        entries.read_all(link, objects, findings)
        if options.reset:
            say("probe: NMT reset node, then every entry again")
            entries.reset_and_reread(link, objects, findings, put_back, options.boot_timeout_s)
        say("probe: TPDO transmission types, abort codes, SYNC producer, block transfer, node guarding, LSS")
        services.tpdo_transmission_types(link, put_back, objects, findings)
        aborts.probe_aborts(link, put_back, objects, findings)
        services.sync_producer(link, put_back, findings)
        services.block_and_segmented(link, put_back, objects, findings)
        services.node_guarding(link, objects, findings)
        services.store_restore_subindices(findings)
        lss_services.probe_lss(link, findings, options.lss_response_s)
    finally:
        findings.put_back_failures = put_back.restore()
        _leave_as_found(link, findings)
        link.close()
    result_todos = apply_findings(draft, todos, findings, options.node_id)
    return ProbeResult(findings, result_todos, time.monotonic() - started, link.requests)
