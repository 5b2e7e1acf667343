"""Writes of the TPDO parameters CiA 301 lets a device change only while the TPDO is not valid, put back the same
way after the test."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import COB_ID_INVALID
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.notes import Notes


class WhileInvalid:
    """Writes 18xxh sub 3 (inhibit time) and sub 6 (SYNC start value) with the TPDO not valid: sub 1 bit 31 set
    first, then the entry, then sub 1 as it was; puts them back the same way. CiA 301 v4.2.0 §7.5.2.37 lets a
    device refuse a change of either while the TPDO exists (open reading tpdo-inhibit-and-sync-start-fixed-while-
    valid)."""

    def __init__(self, dut: DeviceLink, notes: Notes) -> None:
        self._dut = dut
        self._notes = notes
        self._undo: list[tuple[int, int, bytes]] = []

    def write(self, comm: int, sub: int, data: bytes) -> None:
        if not any(k == (comm, sub) for *k, _ in self._undo):
            self._undo.append((comm, sub, self._dut.read(comm, sub)))
        self._invalid_around(comm, lambda: self._dut.write(comm, sub, data))

    def _invalid_around(self, comm: int, action: Callable[[], None]) -> None:
        cob_id = self._dut.read_uint(comm, 1)
        entry = self._dut.profile.entry(comm, 1)
        if cob_id & COB_ID_INVALID or entry is None or not entry.writable:
            action()
            return
        self._dut.write(comm, 1, (cob_id | COB_ID_INVALID).to_bytes(4, "little"))
        try:
            action()
        finally:
            self._dut.write(comm, 1, cob_id.to_bytes(4, "little"))
        self._notes.note(f"{comm:04X}h.01 bit 31 set around the write (TPDO not valid), then {cob_id:08X}h again")

    def restore(self) -> list[str]:
        """Put back what ``write`` changed (newest first); what could not be put back."""
        problems = []
        for comm, sub, data in reversed(self._undo):
            try:
                if self._dut.read(comm, sub) != data:
                    self._invalid_around(comm, partial(self._dut.write, comm, sub, data))
            except (SdoAbortedError, AssertionError) as exc:
                if not self._dut.usable:
                    break
                problems.append(f"{comm:04X}h.{sub:02X}: {exc}")
        self._undo.clear()
        return problems
