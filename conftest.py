"""pytest options and hooks of the conformance suite (the only place they are declared).

Fixtures live in fixtures/; this file declares the command-line options, loads the device
profile once, selects tests by capability, and sets up the report outputs.
"""

from __future__ import annotations

import gc
from pathlib import Path

import pytest

from encoder_conformance.errors import BusLostError, BusSetupError, DutLostError, ProfileError
from encoder_conformance.plugin import (
    bus_trace,
    hypothesis_profiles,
    lifecycle,
    outcomes,
    reporting,
    run_record,
    selection,
    shuffle,
    verdicts,
)
from encoder_conformance.plugin import history_hook as history
from encoder_conformance.plugin import options as opts

pytest_plugins = ["fixtures.bus", "fixtures.simulator", "fixtures.dut", "fixtures.periodic", "fixtures.evidence",
                  "fixtures.emcy", "fixtures.tpdo",
                  "fixtures.lss", "fixtures.encoder",
                  "encoder_conformance.plugin.progress"]

hypothesis_profiles.load()  # ci, bench, soak, dev (HYPOTHESIS_PROFILE)


def pytest_addoption(parser: pytest.Parser) -> None:
    opts.add_options(parser)
    run_record.add_option(parser.getgroup("encoder-conformance"))
    history.add_option(parser.getgroup("encoder-conformance"))
    shuffle.add_option(parser.getgroup("encoder-conformance"))


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
    reporting.start_background_writers(session.config)
    run_record.start(session.config)
    lifecycle.start(session.config)
    if lifecycle.state_of(session.config) is not None:
        gc.disable()  # until the tests are collected (a full pass during collection took 60-100 ms): see below


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    selection.parametrize_from_profile(metafunc)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    selection.apply_capability_marks(config, items)
    shuffle.shuffle(config, items)  # --shuffle SEED: a test that inherits a state shows
    selection.destructive_last(items)


def pytest_collection_finish(session: pytest.Session) -> None:
    lifecycle.note_collected(session)
    if lifecycle.state_of(session.config) is not None:
        # what a conformance run has built so far (modules, profile, ~700 items) lives until its end: the
        # garbage collector's full passes during the tests need not walk it again and again
        gc.freeze()
        gc.enable()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    lifecycle.stop_if_gone(item.config)  # the device or bus is gone: one reason, the rest not run
    result = yield
    lifecycle.stop_if_gone(item.config)
    return result


def pytest_runtest_setup(item: pytest.Item) -> None:
    selection.check_gates(item)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]):
    outcome = yield
    report = outcome.get_result()
    exc = call.excinfo.value if call.excinfo is not None else None
    if isinstance(exc, BusLostError):
        # the tester lost its bus: not the device's failure, and the test did not run to its end
        report.outcome = "skipped"
        report.longrepr = (str(item.path), item.location[1] or 0, f"not run to the end: {exc}")
    elif isinstance(exc, DutLostError):
        report.longrepr = str(exc)  # one line: the device is gone (note_loss adds the last frames sent)
    outcomes.classify(item, call, report)  # no finding about the device: an internal error of the tool
    lifecycle.note_loss(item, report)  # the device stopped answering in this test: it fails, naming the frames
    verdicts.judge(item, report, exc)  # a broken inferred rule: a warning, or a failure with --strict-inferred
    reporting.attach_evidence(item, call, report)
    run_record.note_report(item, report)
    lifecycle.note_report(item.config, report)


def pytest_report_header(config: pytest.Config) -> list[str]:
    return [*reporting.header_lines(config), *shuffle.header(config)]


@pytest.hookimpl(optionalhook=True)
def pytest_html_report_title(report) -> None:
    report.title = "CANopen encoder conformance report"


@pytest.hookimpl(optionalhook=True)
def pytest_html_results_summary(prefix: list[str], summary: list[str], postfix: list[str], session) -> None:
    reporting.html_summary(prefix, session, run_record.completed(session), lifecycle.summary_lines(session.config))


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    reporting.terminal_summary(terminalreporter, config, lifecycle.summary_lines(config))


@pytest.hookimpl(tryfirst=True)
def pytest_keyboard_interrupt(excinfo) -> None:
    lifecycle.give_back_now(excinfo)  # Ctrl-C or a stop: before pytest formats the traceback (slow)


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_sessionfinish(session: pytest.Session, exitstatus: int):
    lifecycle.give_back(session.config)  # after Ctrl-C or a stop: first thing, while the bus is still open
    result = yield
    xmlpath = session.config.option.xmlpath  # written by pytest's junitxml in the hooks just run
    if xmlpath:
        outcomes.junit_internal_errors_as_errors(Path(xmlpath))
    bus_trace.write_unsettled(session.config)  # a test stopped before its teardown report keeps its trace
    if not lifecycle.ended_early(session.config):
        reporting.fail_all_skipped(session)
    lifecycle.final_exit_status(session)
    run_record.finish(session)
    history.record(session)  # the history entry, and an acceptance run's certificate
    reporting.finish_background_writers(session.config)
    return result
