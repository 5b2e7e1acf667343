"""The only ways a test ends without a verdict, each typed (``coverage.Kind``, ``coverage.Hold``).

Suites and fixtures never call ``pytest.skip`` themselves (``tests/test_architecture.py`` holds them to it): a scope
skip says why the check is outside the run (``not_applicable``, ``not_equipped``, ``not_selected``), a check in scope
that could not judge says which :class:`~encoder_conformance.coverage.Hold` kept it (``not_judged``). The plugin
reads the kind from the exception (``kind_and_hold``) and books it: a not-testable check makes its area INCOMPLETE.
"""

from __future__ import annotations

from typing import NoReturn

import pytest

from encoder_conformance.coverage import Hold, Kind, kind_of
from encoder_conformance.errors import NotJudged

#: user properties of a skipped report: its kind and, in scope, its hold
KIND_PROPERTY = "skip_kind"
HOLD_PROPERTY = "hold"


class TypedSkip(pytest.skip.Exception):  # type: ignore[name-defined]
    """pytest's skip, carrying why (a scope kind, or a hold for a check in scope)."""

    def __init__(self, kind: Kind, detail: str, hold: Hold | None = None) -> None:
        prefix = f"{kind.value}: "
        super().__init__(detail if detail.startswith(prefix) else prefix + detail)
        self.kind = kind
        self.hold = hold


def not_applicable(detail: str) -> NoReturn:
    """Out of scope: the profile (or the device's documented answer) does not apply this check."""
    raise TypedSkip(Kind.NOT_APPLICABLE, detail)


def not_equipped(detail: str) -> NoReturn:
    """Out of scope: the station lacks what the check needs (power switch, shaft drive, EMCY stimulus, ...)."""
    raise TypedSkip(Kind.NOT_EQUIPPED, detail)


def not_selected(detail: str) -> NoReturn:
    """Out of scope: the run's options left the check out (e.g. no --allow-destructive)."""
    raise TypedSkip(Kind.NOT_SELECTED, detail)


def not_judged(hold: Hold, detail: str) -> NoReturn:
    """In scope, but the check could not judge the device: ``hold`` says why (not testable or inconclusive)."""
    raise TypedSkip(hold.kind, detail, hold)


def skip_text(text: str, hold: Hold | None = None) -> NoReturn:
    """A reason composed elsewhere (a capture's or a chooser's text) with its hold where it has one, else typed by
    its first words; an untyped text is not testable (``Hold.UNTYPED``), never out of scope."""
    if hold is not None:
        raise TypedSkip(hold.kind, text, hold)
    kind = kind_of(text)
    raise TypedSkip(kind, text, Hold.UNTYPED if kind.in_scope else None)


def kind_and_hold(exc: BaseException | None, message: str) -> tuple[Kind, Hold | None]:
    """Why a skipped report did not judge: from a typed exception, else (a skip marker, a library's skip) from the
    message's first words, an unknown one counting as not testable."""
    if isinstance(exc, TypedSkip):
        return exc.kind, exc.hold
    if isinstance(exc, NotJudged):
        return exc.hold.kind, exc.hold
    kind = kind_of(message)
    return kind, (Hold.UNTYPED if kind.in_scope else None)


def skip_reason(report: pytest.TestReport) -> str:
    """The reason text of a skip report (pytest keeps it as (file, line, 'Skipped: reason'))."""
    longrepr = report.longrepr
    text = str(longrepr[2]) if isinstance(longrepr, tuple) else str(longrepr)
    return text.removeprefix("Skipped: ")


def book(report: pytest.TestReport, exc: BaseException | None) -> None:
    """Mark a skipped report with its kind and hold (user properties: the run record and JUnit read them)."""
    if isinstance(exc, TypedSkip) and isinstance(report.longrepr, tuple):  # pytest names a subclass in its text
        path, line, _ = report.longrepr
        report.longrepr = (path, line, f"Skipped: {exc.msg}")
    kind, hold = kind_and_hold(exc, skip_reason(report))
    report.user_properties.append((KIND_PROPERTY, kind.value))
    if hold is not None:
        report.user_properties.append((HOLD_PROPERTY, hold.name))


def booked(report: pytest.TestReport) -> tuple[Kind | None, Hold | None]:
    """The kind and hold ``book`` gave a skipped report (None, None where it has none)."""
    props = {str(name): str(value) for name, value in report.user_properties}
    kind = props.get(KIND_PROPERTY)
    return (Kind(kind) if kind else None), Hold.__members__.get(props.get(HOLD_PROPERTY, ""))
