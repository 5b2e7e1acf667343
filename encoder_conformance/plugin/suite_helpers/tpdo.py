"""The TPDO a transmission test uses, chosen the same way by every TPDO suite, and the report's note of the choice;
the test is skipped where the profile has none that qualifies."""

from __future__ import annotations

from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.custody import SettingsJournal
from encoder_conformance.dut.tpdo import NoUsableTpdo, TpdoUnderTest
from encoder_conformance.plugin.evidence import Evidence
from encoder_conformance.plugin.skips import skip_text


def tpdo_under_test(dut: DeviceUnderTest, sub: int, evidence: Evidence, journal: SettingsJournal,
                    usable_types: list[int]) -> TpdoUnderTest:
    """The TPDO to use (``dut.tpdo.for_test``: sub-index ``sub`` writable, a type of ``usable_types``), enabled for
    the test where it is disabled; the choice's deviations and notes in the evidence. Skips where no TPDO
    qualifies."""
    try:
        return dut.tpdo.for_test(sub, usable_types, journal, evidence)
    except NoUsableTpdo as exc:
        skip_text(str(exc), exc.hold)
