"""What each verdict rests on, and the outcome of a broken inferred rule.

A verdict rests on a CiA clause (``cia``), the device's manual (``manual``) or our own reading of
what neither says (``inferred``). Only the first two fail a device by default: a test whose only
problems break inferred rules passes with a warning (JUnit property ``verdict=warning``, listed in
the summaries) unless the run asks for ``--strict-inferred``. The summaries count verdicts per basis.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import pytest

from .evidence import BASES, EVIDENCE

STRICT_OPTION = "--strict-inferred"


@dataclass
class VerdictTally:
    """Verdicts of the run per basis and outcome, and the warnings (tests that broke only inferred rules)."""

    counts: Counter[tuple[str, str]] = field(default_factory=Counter)  # (basis, outcome) -> tests
    warnings: list[tuple[str, list[str]]] = field(default_factory=list)  # (test id, problems)

    def lines(self) -> list[str]:
        """One line per basis: 'cia: 300 passed, 1 failed'."""
        lines = []
        for basis in BASES:
            parts = [f"{n} {outcome}" for (b, outcome), n in sorted(self.counts.items()) if b == basis and n]
            if parts:
                lines.append(f"{basis}: {', '.join(parts)}")
        return lines


TALLY = pytest.StashKey[VerdictTally]()


def add_option(group) -> None:  # noqa: ANN001 - pytest's OptionGroup
    group.addoption(STRICT_OPTION, action="store_true", default=False,
                    help="judge rules we only inferred (a manual's silence, an example) as failures; by default "
                         "a device that breaks only such rules passes with a warning")


def strict(config: pytest.Config) -> bool:
    return bool(config.getoption(STRICT_OPTION, default=False))


def tally_of(config: pytest.Config) -> VerdictTally:
    if TALLY not in config.stash:
        config.stash[TALLY] = VerdictTally()
    return config.stash[TALLY]


def add_property(item: pytest.Item, report: pytest.TestReport, name: str, value: str) -> None:
    """On the call report (the summaries read it) and the item (JUnit writes the teardown report's copy)."""
    report.user_properties.append((name, value))
    item.user_properties.append((name, value))


def judge(item: pytest.Item, report: pytest.TestReport) -> None:
    """Set the call report's outcome from what the test's verdict rests on, and count it."""
    evidence = item.stash.get(EVIDENCE, None)
    if evidence is None or report.when != "call" or report.skipped:
        return
    hard_failure = report.failed
    basis = evidence.verdict_basis(hard_failure)
    add_property(item, report, "verdict_basis", basis)
    if evidence.basis_source:
        add_property(item, report, "verdict_source", evidence.basis_source)
    outcome = report.outcome
    if evidence.inferred and not hard_failure:
        problems = [p.describe() for p in evidence.inferred]
        for problem in problems:
            add_property(item, report, "inferred_problem", problem)
        if strict(item.config):
            report.outcome = "failed"
            report.longrepr = f"broke rule(s) we inferred ({STRICT_OPTION}):\n" + "\n".join(problems)
            outcome = "failed"
        else:
            add_property(item, report, "verdict", "warning")
            tally_of(item.config).warnings.append((item.nodeid, problems))
            outcome = "warning"
    tally_of(item.config).counts[(basis, outcome)] += 1


def terminal_lines(config: pytest.Config) -> tuple[list[str], list[str]]:
    """(verdicts per basis, warnings) for the terminal summary."""
    tally = tally_of(config)
    warnings = [f"{test}: {problem}" for test, problems in tally.warnings for problem in problems]
    return tally.lines(), warnings

