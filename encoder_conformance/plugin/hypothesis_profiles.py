"""The suite's hypothesis profiles, chosen with HYPOTHESIS_PROFILE (default: ``ci`` under CI, else ``dev``).

- ``ci``: 50 examples per test, derandomized (every run sends the same examples, so ``--hypothesis-seed``
  has no effect and a failure repeats by running again), no example database;
- ``bench``: 500 examples, random (a failure's seed is in the report: ``--hypothesis-seed=N`` replays it);
  bound its time on a device with ``--fuzz-budget`` / ``--budget``;
- ``soak``: 20,000 examples for long unattended bench runs (use with ``--fuzz-budget``);
- ``dev``: 30 random examples, for work on the suites.

Loaded before hypothesis is first used, not before (importing it costs ~0.2 s of every run's start-up): a session
loads the profile at configure time where hypothesis is already imported or one of its options is given (its
plugin imports it then, and ``--hypothesis-profile ci`` needs ours registered), else just before pytest imports a
test module that may use it: one of ``SUITES_USING_HYPOTHESIS``, or any module outside the suites (the self-tests).
A settings object made at a module's import takes the profile loaded at that time, so no module of those is
imported before. An acceptance run, whose tests use none, does not import hypothesis at all.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from encoder_conformance.paths import SUITES_DIR

if TYPE_CHECKING:
    import pytest

PROFILE_ENV = "HYPOTHESIS_PROFILE"
#: the suite modules that import hypothesis, themselves or through a helper (tests/test_hypothesis_profiles.py
#: imports every other suite module and finds hypothesis not imported)
SUITES_USING_HYPOTHESIS = frozenset({"test_encoder_properties.py", "test_nmt_state_machine.py", "test_sdo_fuzz.py"})
#: hypothesis's pytest options: given one, its plugin imports hypothesis at configure time
HYPOTHESIS_OPTIONS = ("hypothesis_profile", "hypothesis_verbosity", "hypothesis_show_statistics", "hypothesis_seed",
                      "hypothesis_explain")
_LOADED: list[str] = []  # the profile this session loaded (a process may run several sessions, one at a time)


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
    """Register the profiles and load the chosen one (once in a session); its name."""
    if _LOADED:
        return _LOADED[0]
    from hypothesis import settings

    register()
    name = os.getenv(PROFILE_ENV, "ci" if os.getenv("CI") else "dev")
    settings.load_profile(name)
    _LOADED.append(name)
    return name


def configure(config: pytest.Config) -> None:
    """At configure time: load now where hypothesis is imported already or will be by its plugin (one of its
    options given; ``-v`` shows its profile in the header), else wait for a module that uses it."""
    _LOADED.clear()  # a new session chooses again (HYPOTHESIS_PROFILE may differ from the last one's)
    given = any(config.getoption(dest, None) for dest in HYPOTHESIS_OPTIONS)
    if "hypothesis" in sys.modules or given or getattr(config.option, "verbose", 0) >= 1:
        load()


def before_import(module: Path) -> None:
    """Just before pytest imports the test module ``module``: load where it may use hypothesis."""
    if not _LOADED and (module.parent != SUITES_DIR or module.name in SUITES_USING_HYPOTHESIS):
        load()
