"""Settings a test changes by SDO, remembered with their old values and put back after the test."""

from __future__ import annotations

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.errors import DutLostError


class SettingsJournal:
    """Writes through SDO and remembers the old values, to put them back after the test."""

    def __init__(self, dut: DeviceLink) -> None:
        self._dut = dut
        self._undo: list[tuple[int, int, bytes]] = []

    def write(self, index: int, sub: int, data: bytes) -> None:
        self.remember(index, sub)
        self._dut.write(index, sub, data)

    def remember(self, index: int, sub: int, original: bytes | None = None) -> None:
        """Put ``original`` (default: the value read now) back at teardown, for changes made around
        ``write``, e.g. a raw SDO frame that should be refused but may not be."""
        if not any(i == index and s == sub for i, s, _ in self._undo):
            self._undo.append((index, sub, self._dut.read(index, sub) if original is None else original))

    def restore(self) -> list[str]:
        """Write back the old values that differ (newest change first); a write the device refuses in the
        state the others leave it in (e.g. scaling objects before the scaling bit) is tried once more at
        the end. Stops quietly when the device is gone (the run's restore reports it)."""
        refused: list[tuple[int, int, bytes]] = []
        try:
            for index, sub, data in reversed(self._undo):
                if not self._put_back(index, sub, data):
                    refused.append((index, sub, data))
            problems = []
            for index, sub, data in refused:
                try:
                    if self._dut.read(index, sub) != data:
                        self._dut.write(index, sub, data)
                except (SdoAbortedError, AssertionError) as exc:
                    if not self._dut.usable:
                        break
                    problems.append(f"{index:04X}h.{sub:02X}: {exc}")
        except DutLostError:
            problems = []
        self._undo.clear()
        return problems

    def _put_back(self, index: int, sub: int, data: bytes) -> bool:
        """Write ``data`` unless the entry already holds it; False where the device refused (try again later)."""
        try:
            if self._dut.read(index, sub) == data:
                return True
        except SdoAbortedError:
            pass  # write-only or unreadable now: write it anyway
        try:
            self._dut.write(index, sub, data)
        except (SdoAbortedError, AssertionError):
            return not self._dut.usable
        return True
