"""pytest options and hooks of the conformance suite (the only place they are declared).

Fixtures live in fixtures/; this file declares the command-line options, loads the device
profile once, selects tests by capability, and sets up the report outputs.
"""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, settings

from encoder_conformance.errors import BusSetupError, ProfileError
from encoder_conformance.plugin import options as opts
from encoder_conformance.plugin import reporting, selection

pytest_plugins = ["fixtures.bus", "fixtures.simulator", "fixtures.dut", "fixtures.evidence"]

settings.register_profile(
    "ci", max_examples=50, deadline=None, derandomize=True, database=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("bench", max_examples=500, deadline=None, stateful_step_count=30)
settings.register_profile("dev", max_examples=30, deadline=None)
settings.load_profile(os.getenv("HYPOTHESIS_PROFILE", "ci" if os.getenv("CI") else "dev"))


def pytest_addoption(parser: pytest.Parser) -> None:
    opts.add_options(parser)


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "bench: needs bench equipment the simulator provides (power switch)")
    try:
        opts.configure(config)
    except (ProfileError, BusSetupError) as exc:
        raise pytest.UsageError(str(exc)) from None
    reporting.configure_outputs(config)


def pytest_sessionstart(session: pytest.Session) -> None:
    reporting.set_metadata(session.config)


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    selection.parametrize_from_profile(metafunc)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    selection.apply_capability_marks(config, items)


def pytest_runtest_setup(item: pytest.Item) -> None:
    selection.check_gates(item)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]):
    outcome = yield
    reporting.attach_evidence(item, call, outcome.get_result())


def pytest_report_header(config: pytest.Config) -> list[str]:
    return reporting.header_lines(config)


@pytest.hookimpl(optionalhook=True)
def pytest_html_report_title(report) -> None:
    report.title = "CANopen encoder conformance report"


@pytest.hookimpl(optionalhook=True)
def pytest_html_results_summary(prefix: list[str], summary: list[str], postfix: list[str], session) -> None:
    reporting.html_summary(prefix, session)


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    reporting.terminal_summary(terminalreporter, config)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    reporting.fail_all_skipped(session)
