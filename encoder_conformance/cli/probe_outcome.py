"""Whether a probed device was still there at the end: a probe whose device vanished midway (a simulator that ends
its process at NMT reset node, with nothing restarting it) would write a draft of silences; it must not end 0."""

from __future__ import annotations

from encoder_conformance.errors import BusSetupError
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.probe.findings import Findings
from encoder_conformance.probe.link import ProbeLink
from encoder_conformance.probe.session import ProbeOptions

RESTART_HINT = ("a firmware simulator that ends its process at NMT reset node needs the restart loop (README "
                '"Firmware CI"; firmware-ci --probe runs it for you), or probe with --no-reset')


def vanished(options: ProbeOptions, findings: Findings) -> str | None:
    """Why the probe's result cannot be trusted (the device stopped answering), or None: it still answers 1000h
    (asked again for up to the boot time-out, as the probe asks at its start)."""
    try:
        link = ProbeLink(options.bus, options.node_id, options.sdo_timeout_s)
    except BusSetupError as exc:
        return f"the bus could not be opened again after the probe: {exc}; nothing written; exit " \
               f"{RunExit.COULD_NOT_TEST}"
    try:
        answers = not link.first_answer(options.boot_timeout_s).silent
    finally:
        link.close()
    if answers:
        return None
    after_reset = " (no boot-up after the probe's NMT reset node)" if options.reset and not findings.reset else ""
    return (f"node {options.node_id} stopped answering during the probe{after_reset}: the draft would rest on "
            f"silences; nothing written; exit {RunExit.COULD_NOT_TEST}. {RESTART_HINT}")
