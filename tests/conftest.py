"""The self-tests never write into the repository's reports/history.sqlite: every conformance run they start,
in this process or a child process, records into a temporary history database instead. ``preload_library``:
the user-space SocketCAN bus's library, built once (its tests skip where it cannot be built). ``full_runs``: the
full suites against a profile's fault-free twin, once per session; ``fault_runs``: a fault's targeted run, once
per session (tests/suite_session.py); ``runs_ahead``: the slow modules' sessions, started in the background when the
session starts (tests/runs_ahead.py), beside the other modules, which leave ``FOREGROUND_SLOTS`` (a module
attribute, default 2) of the session slots free for their own processes."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from encoder_conformance.history.db import ENV_VAR
from encoder_conformance.runs.session_slots import SESSION_SLOTS
from encoder_conformance.vcan import BuildError, library
from tests.runs_ahead import RunsAhead
from tests.suite_session import PARALLEL_RUNS, FaultRuns, FullRuns

#: session slots a module leaves to its own processes where it declares none (the slow modules declare 0). Two:
#: with one, the background's three sessions beside the quick modules' own runs slowed the full twin runs past a
#: minute (test_twins: FRABA c2-st 69 s, SIKO 1012 82 s against 35-50 s four at a time alone)
FOREGROUND_SLOTS = 2
#: set to 0 to make each slow module's sessions in its own turn instead of ahead, beside the quick modules (on by
#: default since the suite holds under that load: the twin asks for a processor's share of its own, a period check
#: tells the host's lateness from the device's, test_twins judges a run's own time; issue 42's note)
RUNS_AHEAD_ENV = "ENCODER_CONFORMANCE_RUNS_AHEAD"
#: lines for the terminal summary (the session's fixtures end before it is written)
_SUMMARY: list[str] = []


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


@pytest.fixture(scope="session")
def runs_ahead(tmp_path_factory, full_runs, fault_runs):
    """The slow modules' sessions, made once, most of them in the background ahead of their module."""
    ahead = RunsAhead(tmp_path_factory.mktemp, full_runs, fault_runs)
    yield ahead
    ahead.close()
    if ahead.summary_worth_printing():
        _SUMMARY.append(ahead.summary())


def pytest_terminal_summary(terminalreporter):
    for line in _SUMMARY:
        terminalreporter.write_line(line)


def pytest_collection_modifyitems(session, config, items):
    """The modules whose results are made ahead (``sessions_ahead``, ``work_ahead``) run after the others, and a
    module with ``RUNS_LAST`` after those: the quick modules run first, beside the background, which has most of
    those results ready when their turn comes (a module that waited for them in the middle held every quick module
    up behind it). Not where ``RUNS_AHEAD_ENV`` is 0."""
    if os.environ.get(RUNS_AHEAD_ENV) == "0":
        return

    def turn(item) -> int:
        module = getattr(item, "module", None)
        if getattr(module, "RUNS_LAST", False):
            return 2  # times something against the host's load: after the background is done
        return 1 if hasattr(module, "sessions_ahead") or hasattr(module, "work_ahead") else 0

    items.sort(key=turn)  # stable: each module's own order, and the modules' among themselves, kept


@pytest.fixture(autouse=True, scope="session")
def _slow_sessions_started_ahead(request, runs_ahead):
    """Starts every session the selected slow modules declare (``sessions_ahead``), in collection order, at most
    PARALLEL_RUNS suite sessions at a time in the whole process; not where ``RUNS_AHEAD_ENV`` is 0."""
    SESSION_SLOTS.set_limit(PARALLEL_RUNS)
    if os.environ.get(RUNS_AHEAD_ENV) == "0":
        yield
        SESSION_SLOTS.set_limit(None)
        return
    modules = list(dict.fromkeys(item.module for item in request.session.items if hasattr(item, "module")))
    for module in modules:
        declare = getattr(module, "work_ahead", None)
        if declare is not None:
            runs_ahead.start(declare(runs_ahead), side=True)
    for module in modules:
        declare = getattr(module, "sessions_ahead", None)
        if declare is not None:
            runs_ahead.start(declare(runs_ahead))
    yield
    SESSION_SLOTS.set_limit(None)


@pytest.fixture(autouse=True, scope="module")
def _foreground_slots(request):
    """While a module runs, background sessions leave it the slots it declares (FOREGROUND_SLOTS)."""
    with SESSION_SLOTS.reserved(getattr(request.module, "FOREGROUND_SLOTS", FOREGROUND_SLOTS)):
        yield
