"""Runs a hypothesis test in rounds so that a wall-clock budget can end it (hypothesis has no time limit).

Without a budget the test runs once with the profile's settings. With one (``--fuzz-budget``), it runs in
rounds of ``ROUND_EXAMPLES`` examples, round n with seed base + n, until the profile's example count is
reached or the budget is spent: a spent budget then costs at most the rest of one round of examples that
return at once (rejecting them instead would make hypothesis run a hundred per example sent).

Seeds: a derandomized profile (``ci``) sends the same examples every run, with or without a budget
(base 0), and ignores ``--hypothesis-seed``; a random profile (``bench``, ``soak``, ``dev``) takes the
base from ``--hypothesis-seed`` or draws one, and the report names it for the rerun.
"""

from __future__ import annotations

import random
from collections.abc import Callable

from hypothesis import seed, settings

from encoder_conformance.dut.link.time_budget import BUDGET

ROUND_EXAMPLES = 50


def base_seed(profile: settings, forced: int | None, budget_s: float | None) -> int | None:
    """The seed of the first round; None: one derandomized run."""
    if profile.derandomize:
        return None if budget_s is None else 0
    return forced if forced is not None else random.getrandbits(64)


def run_rounds(make_test: Callable[[int], Callable[[], None]], total: int, base: int | None,
               budget_s: float | None, spent: Callable[[], bool]) -> int:
    """Run the test ``make_test(max_examples)`` builds, ``total`` examples in all; the number of rounds run."""
    if budget_s is None:
        test = make_test(total)
        (test if base is None else seed(base)(test))()
        return 1
    assert base is not None
    rounds, sent = 0, 0
    with BUDGET.booking("generation"):  # a budget the user gave: owed by choice, frames and all
        while sent < total and not spent():
            count = min(ROUND_EXAMPLES, total - sent)
            seed(base + rounds)(make_test(count))()
            rounds, sent = rounds + 1, sent + count
    return rounds
