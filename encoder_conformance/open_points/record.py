"""The record of one open reading (see the package docstring)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass


@dataclass(frozen=True)
class OpenReading:
    """One point the texts leave open, the readings accepted, and the twin variant that plays the other one."""

    point: str  #: short id, e.g. "lss-node-id-activation"
    question: str  #: what the text leaves open, in one sentence
    source: str  #: where: document, version, section (and the sentence quoted), or the manual's section
    readings: tuple[str, ...]  #: every reading the suites accept (the twin's default first)
    variant: str  #: the simulator variant (``--sim-fault NAME``) that plays a reading the default twin does not
    variant_text: str  #: what the variant does, one line (``encoder-conformance faults`` lists it)
    modules: tuple[str, ...]  #: suite modules (stems under suites/) whose verdicts rest on this point
    requires: tuple[str, ...] = ()  #: profile capabilities the point needs (all of them); "lss:SERVICE" an LSS service
    excluded_by_effects: tuple[str, ...] = ()  #: quirk effects whose documented behaviour the variant would break
    requires_effects: tuple[str, ...] = ()  #: quirk effects (all of them) whose manual sentence opens the point
    #: False: the variant runs on a twin of its own (one that keeps the device out of operational would leave the
    #: tests of another reading on the same twin untested)
    shares_twin: bool = True
    #: the run's verdict a conformant device playing this reading earns: "INCOMPLETE" where the reading keeps checks
    #: from running (a device that keeps an error and so never stays operational), else "PASS"
    verdict: str = "PASS"

    def applies_to(self, capabilities: Iterable[str], effects: Iterable[str]) -> bool:
        """Whether a profile with these (truthy) capabilities and quirk effects can play this reading."""
        present, quirks = set(capabilities), set(effects)
        return (set(self.requires) <= present and set(self.requires_effects) <= quirks
                and not (set(self.excluded_by_effects) & quirks))
