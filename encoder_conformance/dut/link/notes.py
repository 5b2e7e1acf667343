"""What the DUT layer tells a test's report beside its verdict: notes and documented deviations (the test's
evidence, ``plugin/evidence.py``, has these methods; the DUT layer sees only this much of it)."""

from __future__ import annotations

from typing import Protocol


class Notes(Protocol):
    """Where a DUT helper notes what it did (a setting changed for the test, an error cleared) and the documented
    deviations it relied on."""

    def note(self, text: str) -> None: ...

    def deviation(self, quirk_id: str, text: str) -> None: ...
