"""``--shuffle SEED``: run the modules, and the tests inside each module, in a random (replayable) order.

A test must own its preconditions: it brings the device into the state it needs and leaves nothing
active for the next test. Shuffling shows where one does not: the outcomes of a shuffled run must
equal those of the usual order (tests/test_shuffled_order.py). A module's tests stay together, so
module-scoped fixtures (a periodic capture, a mapping) are set up once as usual; tests that change
what the device remembers stay last (selection.destructive_last sorts after the shuffle, stably).
"""

from __future__ import annotations

import random
from itertools import groupby

import pytest

from encoder_conformance.plugin.option_table import pytest_name

OPTION = pytest_name("--shuffle")  # declared in option_table.py


def shuffle(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Shuffle ``items`` in place by module, then inside each module (no-op without --shuffle)."""
    seed = config.getoption(OPTION)
    if seed is None:
        return
    draw = random.Random(seed)
    modules = [list(group) for _, group in groupby(items, key=lambda item: item.nodeid.split("::")[0])]
    draw.shuffle(modules)
    for module in modules:
        draw.shuffle(module)
    items[:] = [item for module in modules for item in module]


def header(config: pytest.Config) -> list[str]:
    seed = config.getoption(OPTION)
    return [] if seed is None else [f"test order: shuffled with --shuffle {seed}"]
