"""The hook hub of the conformance plugin: every pytest hook the suite implements, each delegating to the
module of its concern. Registered by the ``pytest11`` entry point (and named in conftest.py, for a checkout
used without installing): ``pytest --ec-profile ...`` works wherever the package is installed.

Inert in a pytest session that is not about the suites (another project's tests in the same environment):
its options exist (prefixed ``--ec-``), nothing else happens, and the modules behind the hooks are not even
imported (plugin/activation.py). Registered among the other plugins' entry points, not after them as
a conftest.py is: the hooks whose order against other plugins shows (the report wrapper, the header, the
terminal summary) say ``tryfirst``. Kept out of the package's ``__init__`` so that importing one plugin module
(``plugin.evidence`` from a suite helper) does not import them all.
"""

from __future__ import annotations

import gc
from collections.abc import Generator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from encoder_conformance.errors import (
    BusLostError,
    BusSetupError,
    DutLostError,
    NotJudged,
    ProfileError,
)
from encoder_conformance.plugin import option_table
from encoder_conformance.plugin.activation import LazyModule, is_ours

if TYPE_CHECKING:
    from encoder_conformance.plugin import (
        allure_labels,
        allure_run,
        bus_trace,
        hypothesis_profiles,
        junit_coverage,
        late_frames,
        lifecycle,
        outcomes,
        reporting,
        run_record,
        selection,
        shuffle,
        skips,
        time_budget,
        twin_launch,
        verdicts,
    )
    from encoder_conformance.plugin import history_hook as history
    from encoder_conformance.plugin import options as opts
else:  # imported at their first use, then in place of their LazyModule: only in a session of ours (activation.py)
    (allure_labels, allure_run, bus_trace, hypothesis_profiles, junit_coverage, late_frames, lifecycle, outcomes,
     reporting, run_record, selection, shuffle, skips, time_budget, twin_launch, verdicts, history, opts) = (
        LazyModule(f"encoder_conformance.plugin.{name}", globals(), alias) for name, alias in (
            ("allure_labels", "allure_labels"), ("allure_run", "allure_run"), ("bus_trace", "bus_trace"),
            ("hypothesis_profiles", "hypothesis_profiles"), ("junit_coverage", "junit_coverage"),
            ("late_frames", "late_frames"), ("lifecycle", "lifecycle"), ("outcomes", "outcomes"),
            ("reporting", "reporting"), ("run_record", "run_record"), ("selection", "selection"),
            ("shuffle", "shuffle"), ("skips", "skips"), ("time_budget", "time_budget"), ("twin_launch", "twin_launch"),
            ("verdicts", "verdicts"), ("history_hook", "history"), ("options", "opts")))

pytest_plugins = ["encoder_conformance.plugin.progress"]

_ACTIVE = pytest.StashKey[bool]()
#: the session configured last is a conformance session (pytest-html's title hook and the interrupt hook get no
#: config)
_OURS = [False]

#: markers of the suites (registered here, so that --strict-markers holds wherever the suites run)
MARKERS = (
    "bench: needs bench equipment the simulator provides (power switch)",
)


def _active(config: pytest.Config) -> bool:
    return config.stash.get(_ACTIVE, False)


def pytest_addoption(parser: pytest.Parser) -> None:
    option_table.add_pytest_options(parser)  # every row of plugin/option_table.py, prefixed


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config: pytest.Config) -> None:
    config.stash[_ACTIVE] = is_ours(config)  # the suites' own session, or the self-tests of their checkout
    _OURS[0] = _active(config)
    if not _active(config):
        return
    hypothesis_profiles.configure(config)  # ci, bench, soak, dev (HYPOTHESIS_PROFILE): now, or before it is used
    for marker in MARKERS:
        config.addinivalue_line("markers", marker)
    try:
        opts.configure(config)
    except (ProfileError, BusSetupError) as exc:
        raise pytest.UsageError(str(exc)) from None
    reporting.configure_outputs(config)


def pytest_sessionstart(session: pytest.Session) -> None:
    if not _active(session.config):
        return
    twin_launch.launch_early(session)  # the twin starts while the tests are collected
    reporting.set_metadata(session.config)
    reporting.start_background_writers(session.config)
    run_record.start(session.config)
    time_budget.start(session.config)
    lifecycle.start(session.config)
    if lifecycle.state_of(session.config) is not None:
        gc.disable()  # until the tests are collected (a full pass during collection took 60-100 ms): see below


def pytest_collectstart(collector: pytest.Collector) -> None:
    if isinstance(collector, pytest.Module) and _active(collector.config):
        hypothesis_profiles.before_import(collector.path)  # the module may use hypothesis: its profile first


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if _active(metafunc.config):
        selection.parametrize_from_profile(metafunc)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if not _active(config):
        return
    selection.apply_capability_marks(config, items)
    shuffle.shuffle(config, items)  # --shuffle SEED: a test that inherits a state shows
    selection.destructive_last(items)


def pytest_collection_finish(session: pytest.Session) -> None:
    if not _active(session.config):
        return
    lifecycle.note_collected(session)
    if lifecycle.state_of(session.config) is not None:
        # what a conformance run has built so far (modules, profile, ~700 items) lives until its end: the
        # garbage collector's full passes during the tests need not walk it again and again
        gc.freeze()
    gc.enable()  # paused since session start, or since the command line's start (cli/main.py GC_PAUSED)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Generator[None, object, object]:
    if not _active(item.config):
        return (yield)
    lifecycle.stop_if_gone(item.config)  # the device or bus is gone: one reason, the rest not run
    late_frames.begin(item)  # the "must not come" windows declared from now on are this test's
    with time_budget.measure(item):
        result = yield
    late_frames.end(item)
    lifecycle.stop_if_gone(item.config)
    return result


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtest_teardown(item: pytest.Item, nextitem: pytest.Item | None) -> Generator[None, object, object]:
    if _active(item.config) and nextitem is None and not lifecycle.ended_early(item.config):
        late_frames.linger(item.config)  # the last test: before the session's fixtures end (the twin, the give-back)
    return (yield)


def pytest_runtest_setup(item: pytest.Item) -> None:
    if _active(item.config):
        bus_trace.mark_set_up_start(item)  # before the fixtures: their frames belong in the test's trace
        selection.check_gates(item)


def pytest_unconfigure(config: pytest.Config) -> None:
    if _active(config):
        twin_launch.abandon(config)  # launched, but no test asked for it


@pytest.hookimpl(hookwrapper=True, tryfirst=True)  # outermost: others' wrappers see the report before ours judges
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Generator[None, Any, None]:
    outcome = yield
    if not _active(item.config):
        return
    report = outcome.get_result()
    exc = call.excinfo.value if call.excinfo is not None else None
    if isinstance(exc, BusLostError):
        # the tester lost its bus: not the device's failure, and the test did not run to its end
        report.outcome = "skipped"
        report.longrepr = (str(item.path), item.location[1] or 0, f"not run to the end: {exc}")
    elif isinstance(exc, NotJudged):
        # in scope, but the device's state or answers left nothing to judge: not testable (or inconclusive)
        report.outcome = "skipped"
        report.longrepr = (str(item.path), item.location[1] or 0, str(exc))
    elif isinstance(exc, DutLostError):
        report.longrepr = str(exc)  # one line: the device is gone (note_loss adds the last frames sent)
    if report.skipped:
        skips.book(report, exc)  # why it did not judge: out of scope, not testable, inconclusive
    outcomes.classify(item, call, report)  # no finding about the device: an internal error of the tool
    late_frames.judge(item, report)  # a frame after a window this test closed fails it (before it reports)
    lifecycle.note_loss(item, report)  # the device stopped answering in this test: it fails, naming the frames
    verdicts.judge(item, report, exc)  # a broken inferred rule: a warning, or a failure with --strict
    reporting.attach_evidence(item, call, report)
    run_record.note_report(item, report)
    if reporting.allure_active(item.config):  # allure says what the run says (status, area, clause, basis)
        allure_labels.amend(item, run_record.result_of(item))
    lifecycle.note_report(item.config, report)


@pytest.hookimpl(trylast=True)  # pytest shows the lines of the hooks called last first: ours above its own
def pytest_report_header(config: pytest.Config) -> list[str]:
    if not _active(config):
        return []
    return [*reporting.header_lines(config), *shuffle.header(config)]


@pytest.hookimpl(optionalhook=True)
def pytest_html_report_title(report: Any) -> None:
    if _OURS[0]:  # pytest-html gives no config here
        report.title = "CANopen encoder conformance report"


@pytest.hookimpl(optionalhook=True)
def pytest_html_results_summary(prefix: list[str], summary: list[str], postfix: list[str],
                                session: pytest.Session) -> None:
    if _active(session.config):
        reporting.html_summary(prefix, session, run_record.completed(session), _run_lines(session.config))


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    if _active(config):
        late_frames.terminal_section(terminalreporter, config)  # frames after the window that proved them absent
        reporting.terminal_summary(terminalreporter, config, lifecycle.summary_lines(config))


def _run_lines(config: pytest.Config) -> list[tuple[str, bool]]:
    """The run's own lines of the HTML summary: the device on the bench, then the late frames."""
    return [*lifecycle.summary_lines(config), *late_frames.summary_lines(config)]


@pytest.hookimpl(tryfirst=True)
def pytest_keyboard_interrupt(excinfo: Any) -> None:
    if _OURS[0]:
        lifecycle.give_back_now(excinfo)  # Ctrl-C or a stop: before pytest formats the traceback (slow)


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> Generator[None, object, object]:
    if not _active(session.config):
        return (yield)
    lifecycle.give_back(session.config)  # after Ctrl-C or a stop: first thing, while the bus is still open
    late_frames.settle(session.config)  # late frames no running test took: run-level checks
    result = yield
    xmlpath = session.config.option.xmlpath  # written by pytest's junitxml in the hooks just run
    if xmlpath:
        outcomes.junit_internal_errors_as_errors(Path(xmlpath))
        late_frames.add_to_junit(Path(xmlpath), session.config)
    bus_trace.write_unsettled(session.config)  # a test stopped before its teardown report keeps its trace
    if not lifecycle.ended_early(session.config):
        reporting.fail_all_skipped(session)
    lifecycle.final_exit_status(session)
    summary = run_record.finish(session)
    if xmlpath and summary is not None:
        junit_coverage.add(Path(xmlpath), summary)  # a CI reading only JUnit sees an INCOMPLETE run as not green
    if summary is not None and (allure_results := reporting.allure_results(session.config)) is not None:
        allure_run.write(allure_results, summary)  # environment (the verdict), categories
    history.record(session)  # the history entry, and an acceptance run's certificate
    reporting.finish_background_writers(session.config)
    return result
