"""The state a reset ends in (power-on, reset node, reset communication): the state the device should enter after
its initialisation, and the one its heartbeat reports once the boot-up has settled (never read by SDO).

CiA 301 v4.2.0 §7.3.2.2 (NMT state diagram): after initialisation the device enters pre-operational autonomously.
A self-starting device enters operational by itself: CiA 302-2 object 1F80h (NMT start-up) bit 3, or the object a
profile's quirk ``nmt_autostart_object`` documents, holding its operational value.
"""

from __future__ import annotations

from dataclasses import dataclass

import can

from encoder_conformance.cia.cia301 import NmtState
from encoder_conformance.dut.link.device import DeviceLink, answer_window
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.nmt.heartbeat_state import is_state_beat
from encoder_conformance.profile import quirk_effects as fx

NMT_STARTUP = 0x1F80  # CiA 302-2: NMT start-up
SELF_STARTING = 0x08  # 1F80h bit 3: the device enters operational by itself
CIA301 = "CiA 301 v4.2.0 §7.3.2.2 (NMT state diagram: after initialisation the device enters pre-operational)"


@dataclass(frozen=True)
class Expected:
    """The state a reset should end in, why (the clause or manual), and the quirk relied on (None: none)."""

    state: NmtState
    why: str
    quirk_id: str | None = None


def expected_after_reset(dut: DeviceLink) -> Expected:
    """Pre-operational, or operational where the documented autostart object or 1F80h bit 3 says so (read by SDO
    now, before the reset: the value a reset reloads is the one the device holds between tests)."""
    found = dut.profile.quirk(fx.NmtAutostartObject)
    if found is not None:
        quirk_id, quirk, params = found.id, found.quirk, found.params
        value = dut.read_uint(params.index, params.subindex)
        where = f"{params.index:04X}h.{params.subindex:02X} = {value:02X}h"
        if value == params.operational_value:
            return Expected(NmtState.OPERATIONAL, f"documented (manual {quirk.manual}, quirk {quirk_id}): {where} "
                                                  f"starts the device after boot-up", quirk_id)
        return Expected(NmtState.PRE_OPERATIONAL, f"{CIA301}; {where} is not the autostart value "
                                                  f"{params.operational_value:02X}h (manual {quirk.manual})", quirk_id)
    if dut.profile.entry(NMT_STARTUP, 0) is not None:
        value = dut.read_uint(NMT_STARTUP)
        if value & SELF_STARTING:
            return Expected(NmtState.OPERATIONAL, f"CiA 302-2 1F80h = {value:08X}h, bit 3 set: a self-starting device")
        return Expected(NmtState.PRE_OPERATIONAL, f"{CIA301}; 1F80h = {value:08X}h, bit 3 clear (CiA 302-2)")
    return Expected(NmtState.PRE_OPERATIONAL, CIA301)


def boot_up_after(dut: DeviceLink, mark: Mark) -> can.Message | None:
    """The boot-up message (00h) after ``mark`` in the log."""
    boots = dut.frames.since(mark, lambda m: dut.is_heartbeat(m) and bytes(m.data) == b"\x00")
    return boots[0] if boots else None


def settled_state(dut: DeviceLink, after: Mark, boot: can.Message, period_ms: int,
                  slack_s: float = 0.0) -> int | None:
    """The state the first heartbeat after ``after`` reports once the settle time after ``boot`` is over (a
    self-starting device may still show pre-operational right after its boot-up); None: no heartbeat came within
    the settle time, the answer window for two periods (a heartbeat owed: the wait ends when it comes; a loaded
    host delivers it late) and ``slack_s``."""
    settle = dut.profile.timing.nmt_settle_ms / 1000
    beat = dut.frames.wait_for(lambda m: is_state_beat(dut, m) and m.timestamp >= boot.timestamp + settle,
                               settle + answer_window(2 * period_ms / 1000) + slack_s, after)
    return beat.data[0] if beat is not None else None
