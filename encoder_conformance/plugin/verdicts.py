"""What each verdict rests on, and the outcome of a broken inferred rule.

A verdict rests on a CiA clause (``cia``), the device's manual (``manual``) or our own reading of
what neither says (``inferred``). Only the first two fail a device by default: a test whose only
problems break inferred rules passes with a warning (JUnit property ``verdict=warning``, listed in
the summaries) unless the run asks for ``--strict`` (pytest: ``--ec-strict``). That holds for a test that records its
problems (``evidence.inferred_problem``) and for one whose verdict rests on ``inferred``
(``evidence.rests_on("inferred", ...)``) and fails an assertion: a finding about the device, judged by
a rule we inferred. An internal error of the tool (``outcomes``) is no verdict: it is counted in no
basis. The summaries count verdicts per basis.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import pytest

from encoder_conformance.errors import DutLostError
from encoder_conformance.plugin.evidence import BASES, EVIDENCE
from encoder_conformance.plugin.option_table import pytest_name
from encoder_conformance.plugin.outcomes import is_internal_error

STRICT_OPTION = pytest_name("--strict")  # pytest's spelling of run/accept --strict


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


def judge(item: pytest.Item, report: pytest.TestReport, exc: BaseException | None = None) -> None:
    """Set the call report's outcome from what the test's verdict rests on, and count it (``exc``: what the
    call raised; a device that stopped answering is no broken inferred rule)."""
    evidence = item.stash.get(EVIDENCE, None)
    if evidence is None or report.when != "call" or report.skipped or is_internal_error(report):
        return
    hard_failure = report.failed
    basis = evidence.verdict_basis(hard_failure)
    add_property(item, report, "verdict_basis", basis)
    if evidence.basis_source:
        add_property(item, report, "verdict_source", evidence.basis_source)
    outcome: str = report.outcome
    if hard_failure and basis == "inferred" and not strict(item.config) and not isinstance(exc, DutLostError):
        # the test's verdict rests on a rule we inferred and its check failed: a warning, as a recorded problem is
        evidence.inferred_problem(failure_text(report), evidence.basis_source or "our reading (no source given)")
        report.outcome, report.longrepr, hard_failure = "passed", None, False
    if evidence.inferred and not hard_failure:
        problems = [p.describe() for p in evidence.inferred]
        for problem in problems:
            add_property(item, report, "inferred_problem", problem)
        if strict(item.config):
            report.outcome = "failed"
            report.longrepr = "broke rule(s) we inferred (--strict):\n" + "\n".join(problems)
            outcome = "failed"
        else:
            add_property(item, report, "verdict", "warning")
            tally_of(item.config).warnings.append((item.nodeid, problems))
            outcome = "warning"
    tally_of(item.config).counts[(basis, outcome)] += 1


def failure_text(report: pytest.TestReport) -> str:
    """A failed report's message without the exception's name (``AssertionError: ``)."""
    crash = getattr(report.longrepr, "reprcrash", None)
    text = str(crash.message) if crash is not None else str(report.longrepr or "")
    text = text.removeprefix("AssertionError: ").split("\nassert ")[0]  # pytest's own explanation: not needed
    return text.strip() or "the check failed"


def terminal_lines(config: pytest.Config) -> tuple[list[str], list[str]]:
    """(verdicts per basis, warnings) for the terminal summary."""
    tally = tally_of(config)
    warnings = [f"{test}: {problem}" for test, problems in tally.warnings for problem in problems]
    return tally.lines(), warnings

