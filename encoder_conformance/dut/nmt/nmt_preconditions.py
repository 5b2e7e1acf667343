"""The error precondition a test owns: no error left active. Shared by the PDO, SYNC, EMCY and CAM suites and the
periodic capture; the NMT states themselves are reached through ``nmt_states`` alone.

- ``clear_left_error``: 1001h shows an error (a communication error a test or trigger left, e.g. a SYNC time-out
  after 1006h was written, a SYNC of the wrong length): NMT reset communication clears it (CiA 301 v4.2.0
  §7.3.2.2.3: the communication is initialised again) and reloads 1000h-1FFFh from what the device stored, which
  between tests is what it holds. A device may keep a communication error until then and stay out of operational
  (CiA 301 v4.2.0 §7.2.8.3.1 error behaviour; open readings sync-consumer-timeout, communication-error-leaves-
  operational).
"""

from __future__ import annotations

from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import format_frames
from encoder_conformance.dut.link.notes import Notes
from encoder_conformance.dut.nmt.persistent_error import (
    error_register,
    kept_error,
    reset_and_read,
)

__all__ = ["clear_left_error", "error_register"]


def clear_left_error(dut: DeviceLink, notes: Notes, why: str, before: int = 0) -> int:
    """Where 1001h shows an error that was not there ``before``: NMT reset communication and its boot-up, noted
    (an AssertionError where no boot-up comes). Returns 1001h after the reset (0: none was needed, or it cleared)."""
    if not dut.usable:
        return 0
    found = error_register(dut)
    if not found or found == before:
        return 0
    if found == kept_error(dut):  # it survived a reset communication already in this run
        return found
    mark, after = reset_and_read(dut)
    if after is None:
        raise AssertionError(f"no boot-up within {dut.profile.timing.bootup_max_ms:.0f} ms after reset communication "
                             f"(sent to clear 1001h = {found:02X}h)\n{format_frames(dut.frames.since(mark)[-8:])}")
    notes.note(f"1001h = {found:02X}h {why}: NMT reset communication to clear it (1001h now {after:02X}h)")
    return after
