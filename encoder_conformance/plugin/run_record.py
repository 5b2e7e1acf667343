"""Collect the run's RunSummary from pytest's reports and write ``run-summary.json`` at the session's end."""

from __future__ import annotations

import time
from datetime import datetime
from pathlib import Path

import pytest

from encoder_conformance.plugin import acceptance, lifecycle, time_budget
from encoder_conformance.plugin.evidence import EVIDENCE
from encoder_conformance.plugin.options import bench_settings, settings_of
from encoder_conformance.plugin.outcomes import is_internal_error
from encoder_conformance.plugin.reporting import IDENTITY, report_dir
from encoder_conformance.plugin.skips import booked, skip_reason
from encoder_conformance.run_summary import Outcome, RunSummary, TestResult, area_of

SUMMARY = pytest.StashKey[RunSummary]()
_STARTED = pytest.StashKey[float]()
_RESULT = pytest.StashKey[TestResult]()  # the item's result once recorded (a teardown error may change it)
KIND_OPTION = acceptance.KIND_OPTION
MESSAGE_LIMIT = 1500  # characters of a failure kept in the summary (the HTML report has it all)


def summary_of(config: pytest.Config) -> RunSummary | None:
    return config.stash.get(SUMMARY, None)


def result_of(item: pytest.Item) -> TestResult | None:
    """The test's result as recorded so far (None before a phase said anything)."""
    return item.stash.get(_RESULT, None)


def start(config: pytest.Config) -> None:
    """A conformance run (one with a report folder) starts its summary."""
    folder = report_dir(config)
    if folder is None:
        return
    settings = settings_of(config)
    loaded = settings.loaded
    station = settings.station
    values = {key: f"{value} (from {settings.bus.sources.get(key, 'default')})"
              for key, value in settings.bus.kwargs.items()}
    values["node-id"] = f"{settings.node_id} (from {settings.node_id_source})"
    values.update(bench_settings(settings, config.getoption("--ec-station"), config.getoption("--ec-shaft-drive")))
    config.stash[_STARTED] = time.monotonic()
    config.stash[SUMMARY] = RunSummary(
        kind=config.getoption(KIND_OPTION, default="run"),
        started=datetime.now().astimezone().isoformat(timespec="seconds"),
        profile_id=loaded.profile.id, profile_sha256=loaded.sha256, settings=values,
        station=getattr(station, "station", None), operator=getattr(station, "operator", None),
        report_dir=str(folder), scope=scope_of(config, values))


def scope_of(config: pytest.Config, settings: dict[str, str]) -> dict[str, str]:
    """What the station is equipped with and what the run selected, declared before the first test: the checks these
    leave out are listed as scope, never counted against the device."""
    scope = {
        "power switch": settings.get("power switch", "none: the power-cycle checks are out of scope"),
        "shaft drive": settings.get("shaft drive", "the twin's shaft" if config.getoption("--ec-can-interface", None)
                                    is None else "none: the checks that need rotation are out of scope"),
        "destructive checks": ("allowed" if settings_of(config).allow_destructive
                               else "left out: run with --allow-destructive"),
    }
    for option, name in (("keyword", "-k"), ("markexpr", "-m")):
        expression = getattr(config.option, option, "")
        if expression:
            scope[f"selection {name}"] = expression
    return scope


def _stop_verdict(verdict: lifecycle.StopVerdict) -> TestResult:
    """The finding that stopped the run (the start-up check's) as a failed check of its area."""
    return TestResult(verdict.check, verdict.area or "other", "failed", "cia", verdict.source, verdict.message)


def _identity_rejected(config: pytest.Config, reason: str) -> TestResult:
    """The start-up check's verdict on another product (acceptance): a failure of the identity area."""
    identity = settings_of(config).loaded.profile.identity
    return TestResult(acceptance.IDENTITY_CHECK, "identity", "failed", "manual",
                      f"profile identity ({identity.manual})", reason)


def _message(report: pytest.TestReport) -> str:
    longrepr = report.longrepr
    if isinstance(longrepr, tuple):  # a skip: (file, line, "Skipped: reason")
        return skip_reason(report)
    crash = getattr(longrepr, "reprcrash", None)
    text = str(crash.message) if crash is not None else str(longrepr or "")
    return text[:MESSAGE_LIMIT]


def _outcome(report: pytest.TestReport) -> Outcome | None:
    """The test's outcome from this phase's report, or None where the phase says nothing new: "error" only for an
    internal error of the tool (plugin/outcomes.py), a finding about the device in any phase is "failed"."""
    if is_internal_error(report):
        return "error"
    if report.when == "call":
        if report.passed:
            return "warning" if ("verdict", "warning") in report.user_properties else "passed"
        return "failed" if report.failed else "skipped"
    if report.failed:
        return "failed"
    if report.skipped and report.when == "setup":
        return "skipped"
    return None


def _property(report: pytest.TestReport, name: str) -> str | None:
    """The first value of a user property of the report (the plugin writes them as text)."""
    return next((str(v) for k, v in report.user_properties if k == name), None)


def note_report(item: pytest.Item, report: pytest.TestReport) -> None:
    """Add or update the test's result (a teardown error turns a pass into an error)."""
    summary = summary_of(item.config)
    outcome = _outcome(report)
    if summary is None or outcome is None:
        return
    evidence = item.stash.get(EVIDENCE, None)
    basis = _property(report, "verdict_basis")
    source = _property(report, "verdict_source")
    message = _message(report) if outcome in ("failed", "error", "skipped") else ""
    if outcome == "warning":
        message = "; ".join(str(v) for k, v in report.user_properties if k == "inferred_problem")
    lost = _property(report, lifecycle.LOST_PROPERTY)
    if lost and lost not in message:
        message = f"{message[:MESSAGE_LIMIT // 2]}\n{lost}".strip()
    folder = report_dir(item.config)
    trace = None
    if evidence is not None and evidence.trace_path is not None and folder is not None:
        trace = evidence.trace_path.relative_to(folder).as_posix()
    existing = item.stash.get(_RESULT, None)
    if existing is not None:  # a failure in the teardown after the call's verdict
        device_failure = outcome == "failed" and existing.outcome != "failed"
        if device_failure or (outcome == "error" and existing.outcome in ("passed", "warning")):
            existing.outcome, existing.message = outcome, message
        elif lost and lost not in existing.message:  # the device went silent: the frames sent last
            existing.message = f"{existing.message[:MESSAGE_LIMIT // 2]}\n{lost}"
        return
    kind, hold = booked(report) if outcome == "skipped" else (None, None)
    result = TestResult(item.nodeid, area_of(item.nodeid), outcome, basis,
                        source or (evidence.spec if evidence else None), message, round(report.duration, 3), trace,
                        kind.value if kind else None, hold.name if hold else None)
    item.stash[_RESULT] = result
    summary.results.append(result)


def completed(session: pytest.Session) -> RunSummary | None:
    """The summary with what is known at the session's end (identity, device custody, kept traces).

    Called by the HTML report's summary hook too, which pytest-html runs before ``finish`` (inside the
    conftest's sessionfinish wrapper); repeating it is harmless."""
    config = session.config
    summary, folder = summary_of(config), report_dir(config)
    if summary is None or folder is None:
        return None
    identity = config.stash.get(IDENTITY, {})
    summary.identity = dict(identity)
    label = config.getoption("--ec-label-serial", default=None)
    if label is not None:
        summary.identity["serial number (label)"] = str(label)
    summary.duration_s = round(time.monotonic() - config.stash[_STARTED], 2)
    summary.time_budget = time_budget.budget(config)
    summary.exit_code = int(session.exitstatus)
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    summary.deselected = len(getattr(reporter, "stats", {}).get("deselected", [])) if reporter else 0
    state = lifecycle.state_of(config)
    if state is not None:
        # an interrupted run has no verdict either: no PASS (nor a certificate) for what was not run
        interrupted = state.guard.reason if state.guard.signum is not None else None
        summary.could_not_test = state.stopped or interrupted
        summary.device_failed = state.failed.line() if state.failed else None
        summary.not_run = max(0, state.collected - len(state.reported))
        if state.failed and not state.failed.recorded and not any(r.nodeid == state.failed.check
                                                                   for r in summary.results):
            summary.results.insert(0, _stop_verdict(state.failed))
        already = any(r.nodeid == acceptance.IDENTITY_CHECK for r in summary.results)
        if state.rejected and not already:  # completed() runs twice: for the HTML summary, then for the file
            summary.results.insert(0, _identity_rejected(config, state.rejected))
        summary.device_restored = None if state.record is None else state.record.ok
        summary.device_memory = None if state.record is None else state.record.memory
    for result in summary.results:  # traces of passed tests may have been dropped (--trace failed)
        if result.trace and not (Path(folder) / result.trace).exists():
            result.trace = None
    return summary


def finish(session: pytest.Session) -> RunSummary | None:
    """Complete the summary and write it to the report folder."""
    summary = completed(session)
    folder = report_dir(session.config)
    if summary is not None and folder is not None:
        summary.write(folder)
    return summary
