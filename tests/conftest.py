"""The self-tests never write into the repository's reports/history.sqlite: every conformance run they start,
in this process or a child process, records into a temporary history database instead. ``preload_library``:
the user-space SocketCAN bus's library, built once (its tests skip where it cannot be built). ``full_runs``: the
full suites against a profile's fault-free twin, once per session; ``fault_runs``: a fault's targeted run, once
per session (tests/suite_session.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from encoder_conformance.history.db import ENV_VAR
from encoder_conformance.vcan import BuildError, library
from tests.suite_session import FaultRuns, FullRuns


@pytest.fixture(autouse=True, scope="session")
def _history_in_a_temporary_file(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(ENV_VAR, str(tmp_path_factory.mktemp("history") / "history.sqlite"))
        yield


@pytest.fixture(scope="session")
def preload_library() -> Path:
    try:
        return library()
    except BuildError as error:
        pytest.skip(str(error))


@pytest.fixture(scope="session")
def full_runs(tmp_path_factory) -> FullRuns:
    """The full suites against each profile's fault-free twin, run once in the whole self-test session."""
    return FullRuns(tmp_path_factory.mktemp)


@pytest.fixture(scope="session")
def fault_runs(tmp_path_factory) -> FaultRuns:
    """A fault's targeted run against a profile's twin, run once in the whole self-test session."""
    return FaultRuns(tmp_path_factory.mktemp)
