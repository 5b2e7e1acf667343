"""``dut.custody``: the device as the run found it is the run's to give back: access that also works while the run
is stopping, and the journal through which a test's changes are put back."""

from __future__ import annotations

from contextlib import AbstractContextManager

from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.dut.link.device import DeviceLink


class CustodyFace:
    """Custody of the device."""

    def __init__(self, dut: DeviceLink) -> None:
        self._dut = dut

    def access(self) -> AbstractContextManager[DeviceLink]:
        """Device access for the snapshot and the give-back, also while the run is stopping."""
        return self._dut.in_custody()

    def journal(self) -> SettingsJournal:
        """A journal of the writes a test makes, which puts each back afterwards."""
        return SettingsJournal(self._dut)
