"""``dut.tpdo``: the device's TPDOs, as canopen's ``node.tpdo``: ``dut.tpdo[n]`` (``tpdo.Tpdo``: its COB-ID, the
predicate of its frames, its windows), the one a test may use and its set-up for the test, through the test's
settings journal so that the journal puts it back."""

from __future__ import annotations

from encoder_conformance.cia.cia301 import TPDO_COMMUNICATION
from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.notes import Notes
from encoder_conformance.dut.tpdo.tpdo import Tpdo
from encoder_conformance.dut.tpdo.tpdo_choice import NoUsableTpdo, TpdoChoice, choose_tpdo
from encoder_conformance.dut.tpdo.tpdo_under_test import TpdoUnderTest


class Tpdos:
    """The device's TPDOs: ``dut.tpdo[n]``, ``dut.tpdo.at(0x1800)``, and the one a test may use (``choose``)."""

    def __init__(self, dut: DeviceLink) -> None:
        self._dut = dut

    def __getitem__(self, number: int) -> Tpdo:
        return Tpdo(self._dut, number)

    def at(self, comm: int) -> Tpdo:
        """The TPDO whose communication parameter is ``comm`` (18xxh)."""
        return Tpdo(self._dut, comm - TPDO_COMMUNICATION.start + 1)

    def choose(self, sub: int, usable_types: list[int],
               leave_alone: frozenset[tuple[int, int]] = frozenset()) -> TpdoChoice:
        """The first TPDO a test may use (``tpdo_choice.choose_tpdo``); NoUsableTpdo where none qualifies."""
        return choose_tpdo(self._dut, sub, usable_types, leave_alone)

    def chosen(self, journal: SettingsJournal, choice: TpdoChoice) -> TpdoUnderTest:
        """The TPDO ``choice`` names, enabled through ``journal`` where it is disabled."""
        return TpdoUnderTest.chosen(self._dut, journal, choice)

    def for_test(self, sub: int, usable_types: list[int], journal: SettingsJournal, notes: Notes) -> TpdoUnderTest:
        """The TPDO a test uses (``choose``), set up through ``journal`` (which puts it back), the choice's documented
        deviations and notes in ``notes``; NoUsableTpdo (its deviations noted) where none qualifies."""
        try:
            choice = self.choose(sub, usable_types)
        except NoUsableTpdo as exc:
            for quirk_id, text in exc.deviations:
                notes.deviation(quirk_id, text)
            raise
        for quirk_id, text in choice.deviations:
            notes.deviation(quirk_id, text)
        tpdo = self.chosen(journal, choice)
        for note in choice.notes:
            notes.note(note)
        return tpdo
