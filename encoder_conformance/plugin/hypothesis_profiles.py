"""The suite's hypothesis profiles, chosen with HYPOTHESIS_PROFILE (default: ``ci`` under CI, else ``dev``).

- ``ci``: 50 examples per test, derandomized (every run sends the same examples, so ``--hypothesis-seed``
  has no effect and a failure repeats by running again), no example database;
- ``bench``: 500 examples, random (a failure's seed is in the report: ``--hypothesis-seed=N`` replays it);
  bound its time on a device with ``--fuzz-budget`` / ``--budget``;
- ``soak``: 20,000 examples for long unattended bench runs (use with ``--fuzz-budget``);
- ``dev``: 30 random examples, for work on the suites.
"""

from __future__ import annotations

import os

PROFILE_ENV = "HYPOTHESIS_PROFILE"


def register() -> None:
    # imported here, at configure time: a process that preloads the plugin (runs/suite_runner.py) must not have
    # imported hypothesis, which pytest rewrites as a plugin of its own
    from hypothesis import HealthCheck, settings

    settings.register_profile(
        "ci", max_examples=50, deadline=None, derandomize=True, database=None, print_blob=True,
        suppress_health_check=[HealthCheck.too_slow],
    )
    settings.register_profile("bench", max_examples=500, deadline=None, stateful_step_count=30)
    settings.register_profile("soak", max_examples=20_000, deadline=None, stateful_step_count=50,
                              suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("dev", max_examples=30, deadline=None)


def load() -> str:
    """Register the profiles and load the chosen one; its name."""
    from hypothesis import settings

    register()
    name = os.getenv(PROFILE_ENV, "ci" if os.getenv("CI") else "dev")
    settings.load_profile(name)
    return name
