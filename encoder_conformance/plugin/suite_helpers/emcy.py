"""The EMCY suites' access to a device's errors: a trigger the bench and the device offer, and the wait for the
EMCY it causes, judged (a missing EMCY fails the test, or makes it inconclusive where only an inferred rule says
the trigger causes one). Settings a trigger needs (1019h, 1016h) go through the test's settings journal."""

from __future__ import annotations

import can

from encoder_conformance.coverage import Hold
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.bench import BenchActuator
from encoder_conformance.dut.custody import SettingsJournal
from encoder_conformance.dut.emcy import EmcyCobId, EmcyTrigger, emcy_code
from encoder_conformance.dut.link import Mark, format_frames
from encoder_conformance.plugin.evidence import Evidence
from encoder_conformance.plugin.skips import not_equipped, not_judged


class EmcyAccess:
    """A test's way to make the device send an EMCY and to wait for it."""

    def __init__(self, dut: DeviceUnderTest, bench: BenchActuator, journal: SettingsJournal,
                 evidence: Evidence) -> None:
        self.dut = dut
        self._bench = bench
        self._journal = journal
        self._evidence = evidence
        self.used_bench = False

    def trigger(self, repeatable: bool = False, clears: bool = False) -> EmcyTrigger:
        """A trigger that can do what the test needs, noted in the evidence; skips where the bench has none."""
        found = self.dut.emcy.trigger(self._bench, self._journal.write, repeatable, clears)
        if isinstance(found, str):
            not_equipped(f"{found}")
        self.used_bench = self.used_bench or found.clears
        self._evidence.note(f"EMCY trigger: {found.name} (EMCY {found.code:04X}h expected; a bench run adds an entry "
                            "to the error history 1003h each time)")
        return found

    def cob_id(self) -> EmcyCobId:
        return self.dut.emcy.cob_id()

    def wait(self, mark: Mark, trigger: EmcyTrigger, what: str, code: int | None = None,
             judged: bool = False) -> can.Message:
        """The device's EMCY after ``mark`` (with ``code``, default the trigger's). Where none comes and only an
        inferred rule says the trigger causes one, the test is skipped as inconclusive, unless that EMCY is what
        the test ``judged`` (its basis then says whether the failure is a warning); otherwise it fails."""
        wanted = trigger.code if code is None else code
        cob_id = self.cob_id()
        frame = self.dut.frames.wait_for(lambda m: cob_id.matches(m) and emcy_code(m) == wanted,
                                         trigger.answer_s(), mark)
        if frame is not None:
            return frame
        seen = format_frames(self.dut.frames.since(mark))
        if trigger.basis[0] == "inferred" and code is None and not judged:
            not_judged(Hold.NO_EMCY_FROM_TRIGGER,
                       f"no EMCY {wanted:04X}h within {trigger.answer_s() * 1000:.0f} ms after {trigger.name}; only "
                       f"our reading says it causes one ({trigger.basis[1]})\n{seen}")
        raise AssertionError(f"{what}: no EMCY {wanted:04X}h on {cob_id.can_id or 0:03X}h within "
                             f"{trigger.answer_s() * 1000:.0f} ms\n{seen}")
