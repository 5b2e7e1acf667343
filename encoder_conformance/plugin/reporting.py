"""Report outputs: where they go, the header (identity, profile, bus), per-test evidence, summaries."""

from __future__ import annotations

import base64
import html
import time
from collections import Counter
from pathlib import Path

import pytest

from encoder_conformance.coverage import Kind
from encoder_conformance.paths import default_reports_dir
from encoder_conformance.plugin import bus_trace, time_budget
from encoder_conformance.plugin.activation import runs_suites as runs_suites  # where the plugin's modules look
from encoder_conformance.plugin.allure_writer import BackgroundWriter, write_in_background
from encoder_conformance.plugin.evidence import EVIDENCE
from encoder_conformance.plugin.glance import Deviation, PageContext, render, skip_reason_key
from encoder_conformance.plugin.options import bench_settings, settings_of, trace_policy
from encoder_conformance.plugin.skips import booked, skip_reason
from encoder_conformance.plugin.verdicts import add_property, terminal_lines
from encoder_conformance.plugin.verdicts import strict as verdicts_strict
from encoder_conformance.run_summary import RunSummary

REPORT_DIR = pytest.StashKey[Path]()
ALLURE_WRITER = pytest.StashKey[BackgroundWriter]()
IDENTITY = pytest.StashKey[dict[str, str]]()
_CALL_REPORT = pytest.StashKey[pytest.TestReport]()
TRACE_LINKS = ("bus trace (ASC)", "bus trace (candump log)")

#: pytest-html's own "Environment" table (above everything, 20 rows) and its "Summary" heading are hidden:
#: the first screen is ours, and the environment is folded into it (glance's settings)
HIDE_PYTEST_HTML = "<style>#environment-header,#environment,.summary__data>h2{display:none}</style>"


def configure_outputs(config: pytest.Config) -> None:
    """Conformance runs write report.html, junit.xml and allure-results into one folder."""
    if not runs_suites(config) or hasattr(config, "workerinput"):
        return
    settings = settings_of(config)
    given = config.getoption("--ec-report-dir")
    stamp = time.strftime("%Y%m%d-%H%M%S")
    station_reports = settings.station.reports if settings.station is not None else None
    parent = station_reports or default_reports_dir()
    folder = Path(given) if given else parent / f"{stamp}-{settings.loaded.profile.id}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        raise pytest.UsageError(f"--report-dir {folder}: is a file, not a folder; give a folder (it is created if "
                                "missing)") from None
    (folder / "traces").mkdir(exist_ok=True)
    config.stash[REPORT_DIR] = folder
    config.pluginmanager.register(HtmlTable(), "encoder-conformance-html-table")
    option = config.option
    if not getattr(option, "htmlpath", None):
        option.htmlpath = str(folder / "report.html")
        option.self_contained_html = True
    if not getattr(option, "xmlpath", None):
        option.xmlpath = str(folder / "junit.xml")
    if config.getoption("--ec-allure") and not getattr(option, "allure_report_dir", None):
        option.allure_report_dir = str(folder / "allure-results")
        option.clean_alluredir = True


def allure_results(config: pytest.Config) -> Path | None:
    """The folder allure-pytest writes results into in this run (--allure, or its own --alluredir), if any."""
    folder = getattr(config.option, "allure_report_dir", None)
    return Path(folder) if folder else None


def allure_active(config: pytest.Config) -> bool:
    """Whether allure-pytest writes results in this run."""
    return allure_results(config) is not None


def start_background_writers(config: pytest.Config) -> None:
    """Allure's result files are written off the test thread (see allure_writer)."""
    if report_dir(config) is not None and allure_active(config) and (writer := write_in_background()) is not None:
        config.stash[ALLURE_WRITER] = writer


def finish_background_writers(config: pytest.Config) -> None:
    """Every queued report file is on disk before pytest reports the session."""
    writer = config.stash.get(ALLURE_WRITER, None)
    if writer is None:
        return
    for error in writer.close():
        config.get_terminal_writer().line(f"allure results: a file could not be written: {error}", yellow=True)


def report_dir(config: pytest.Config) -> Path | None:
    return config.stash.get(REPORT_DIR, None)


def _metadata(config: pytest.Config) -> dict[str, object] | None:
    try:
        from pytest_metadata.plugin import metadata_key
    except ImportError:  # pragma: no cover - pytest-html always brings pytest-metadata
        return None
    return config.stash.get(metadata_key, None)


def set_metadata(config: pytest.Config) -> None:
    """Profile, its hash and the bus settings with their sources, for the report's environment table."""
    data = _metadata(config)
    if data is None or REPORT_DIR not in config.stash:
        return
    settings = settings_of(config)
    loaded = settings.loaded
    data["Device profile"] = f"{loaded.profile.id} ({loaded.path.name})"
    data["Profile sha256"] = loaded.sha256
    data["Profile files"] = ", ".join(p.name for p in loaded.chain)
    for key, value in settings.bus.kwargs.items():
        data[f"Bus {key}"] = f"{value} (from {settings.bus.sources.get(key, 'default')})"
    data["Node-id"] = f"{settings.node_id} (from {settings.node_id_source})"
    data["SDO abort codes"] = f"{config.getoption('--ec-abort-codes')} (--abort-codes)"
    data["Inferred rules"] = "failures (--strict)" if verdicts_strict(config) else "warnings"
    data["Run kind"] = config.getoption("--ec-run-kind", default="run")
    bench = bench_settings(settings, config.getoption("--ec-station"), config.getoption("--ec-shaft-drive"))
    data.update({key.capitalize(): value for key, value in bench.items()})


def record_identity(config: pytest.Config, identity: dict[str, str]) -> None:
    """Called by the dut fixture once the device's identity has been read."""
    config.stash[IDENTITY] = identity
    data = _metadata(config)
    if data is not None:
        for key, value in identity.items():
            data[f"Device {key}"] = value


def draft_banner(profile) -> str:  # noqa: ANN001 - DeviceProfile
    """The line every report of a profile with open assumptions starts with."""
    return (f"draft profile: {len(profile.todo)} assumptions unconfirmed (profile {profile.id}, todo:); verdicts "
            "that rest on them may be wrong until they are checked against the manual")


def header_lines(config: pytest.Config) -> list[str]:
    settings = settings_of(config)
    loaded = settings.loaded
    lines = [
        *([draft_banner(loaded.profile)] if loaded.profile.todo else []),
        f"device profile: {loaded.profile.id} ({loaded.path}) sha256 {loaded.sha256[:16]}",
        f"bus: {settings.bus.describe()}",
        f"node-id: {settings.node_id} ({settings.node_id_source})",
        f"verdicts: SDO abort codes {config.getoption('--ec-abort-codes')} (--abort-codes); rules we inferred "
        f"judged as {'failures (--strict)' if verdicts_strict(config) else 'warnings (--strict fails them)'}",
    ]
    if settings.shaft_drive is not None:
        lines.append(f"shaft drive: {settings.shaft_drive.spec} (--shaft-drive)")
    folder = report_dir(config)
    if folder:
        lines.append(f"reports: {folder}")
    return lines


def attach_evidence(item: pytest.Item, call: pytest.CallInfo[None], report: pytest.TestReport) -> None:
    """Add measurements, deviations and the trace link to the HTML report and the allure result; after the
    test's last phase, keep or drop its trace (--trace)."""
    evidence = item.stash.get(EVIDENCE, None)
    if evidence is None:
        return
    if report.failed or ("verdict", "warning") in report.user_properties:
        evidence.keep_trace = True
    if report.when == "teardown":
        settle_trace(item)
    if report.when != "call":
        return
    item.stash[_CALL_REPORT] = report
    dut = getattr(item, "funcargs", {}).get("dut")
    if dut is not None:  # what the DUT layer noticed during the test (late SDO answers, family abort codes)
        evidence.notes.extend(dut.tester_notes)
        dut.tester_notes.clear()
    try:
        from pytest_html import extras as html_extras
    except ImportError:  # pragma: no cover - pytest-html is a dependency
        return
    extras = list(getattr(report, "extras", []))
    rows = []
    if evidence.spec:
        rows.append(f"<tr><th>basis</th><td>{html.escape(evidence.spec)}</td></tr>")
    for m in evidence.measurements:
        rows.append(f"<tr><th>measurement</th><td>{html.escape(m.describe())}</td></tr>")
    for quirk_id, text in evidence.deviations:
        rows.append(f"<tr><th>documented deviation</th><td>{html.escape(quirk_id)}: {html.escape(text)}</td></tr>")
    for problem in evidence.inferred:
        rows.append("<tr><th style='color:#b60'>inferred rule broken</th>"
                    f"<td>{html.escape(problem.describe())}</td></tr>")
    for note in evidence.notes:
        rows.append(f"<tr><th>note</th><td>{html.escape(note)}</td></tr>")
    if rows:
        extras.append(html_extras.html(f"<table class='evidence'>{''.join(rows)}</table>"))
    # statistics and plot, one per timing measurement, passed or not (a plot takes ~1 ms: timing_plot.py). The
    # SVG goes in as an <img> data URI: drawn exactly as on its own, untouched by the page's CSS and scripts
    for timing in evidence.timings:
        image = base64.b64encode(timing.svg().encode("utf-8")).decode("ascii")
        extras.append(html_extras.html(f"<div class='timing'>{timing.html_table()}<img src='data:image/svg+xml;"
                                       f"base64,{image}' alt='{html.escape(timing.name)}'></div>"))
        for name, value in timing.properties():
            add_property(item, report, name, value)
    folder = report_dir(item.config)
    if evidence.trace_path is not None and folder:  # written at the teardown if kept (settle_trace), else unlinked
        relative = evidence.trace_path.relative_to(folder)
        extras.append(html_extras.url(relative.as_posix(), name=TRACE_LINKS[0]))
        extras.append(html_extras.url(relative.with_suffix(".log").as_posix(), name=TRACE_LINKS[1]))
    report.extras = extras  # type: ignore[attr-defined]  # why: pytest-html's attribute, undeclared by TestReport
    for quirk_id, _ in evidence.deviations:
        add_property(item, report, "documented_deviation", quirk_id)


def settle_trace(item: pytest.Item) -> None:
    """After the teardown (the test's frames are all in): with --trace failed, a test that passed or
    skipped loses its trace and the report its links; a failure, an error in any phase (teardown too) or a
    warning keeps them, written to their files now (plugin/bus_trace.py)."""
    evidence = item.stash.get(EVIDENCE, None)
    if evidence is None or evidence.trace_path is None:
        return
    keep = trace_policy(item.config) != "failed" or evidence.keep_trace
    trace = evidence.trace
    if trace is not None:
        bus_trace.settle(item.config, trace, keep)
    if keep:
        return
    if trace is None or trace.written:  # files on disk already (allure attached them)
        for path in (evidence.trace_path, evidence.trace_path.with_suffix(".log")):
            path.unlink(missing_ok=True)
    evidence.trace_path = None
    call = item.stash.get(_CALL_REPORT, None)  # pytest-html reads the call's extras at the teardown's logreport
    if call is not None:
        kept = [e for e in getattr(call, "extras", []) if e.get("name") not in TRACE_LINKS]
        call.extras = kept  # type: ignore[attr-defined]  # why: pytest-html's attribute, undeclared by TestReport


class HtmlTable:
    """pytest-html's results table: a skip's log shows its reason, not pytest's (file, line, 'Skipped: ...')."""

    @pytest.hookimpl(optionalhook=True)
    def pytest_html_results_table_html(self, report: pytest.TestReport, data: list[str]) -> None:
        if isinstance(report.longrepr, tuple) and len(report.longrepr) == 3 and data:
            data[0] = html.escape(skip_reason(report)) + "\n"


def deviations_relied_on(config: pytest.Config) -> dict[str, int]:
    """How many verdicts of this run relied on each documented deviation (quirk id -> tests)."""
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    stats = reporter.stats if reporter is not None else {}
    counts: dict[str, int] = {}
    for rep in stats.get("passed", []) + stats.get("failed", []):
        for key, value in rep.user_properties:
            if key == "documented_deviation":
                counts[value] = counts.get(value, 0) + 1
    return counts


def html_summary(prefix: list[str], session: pytest.Session, summary: RunSummary | None,
                 run_lines: list[tuple[str, bool]]) -> None:
    """The report's first screen (plugin/glance.py): verdict, identity, areas, failures; the rest folded."""
    if summary is None:
        return
    config = session.config
    profile = settings_of(config).loaded.profile
    relied = deviations_relied_on(config)
    deviations = [Deviation(qid, q.title, q.manual, q.deviates_from or "", relied.get(qid, 0))
                  for qid, q in profile.quirks.items()]
    environment = {str(k): str(v) for k, v in (_metadata(config) or {}).items()}
    mode = "failures (--strict)" if verdicts_strict(config) else "warnings (--strict fails them)"
    context = PageContext(custody=run_lines, deviations=deviations,
                          draft=draft_banner(profile) if profile.todo else None, todo=list(profile.todo),
                          environment=environment, inferred_mode=mode)
    prefix.append(HIDE_PYTEST_HTML + render(summary, context))


def terminal_summary(terminalreporter, config: pytest.Config,  # noqa: ANN001 - pytest type
                     run_lines: list[tuple[str, bool]]) -> None:
    if REPORT_DIR not in config.stash:
        return
    profile = settings_of(config).loaded.profile
    if profile.todo:
        terminalreporter.write_sep("-", draft_banner(profile).split(";")[0], yellow=True)
    by_basis, warnings = terminal_lines(config)
    if by_basis:
        terminalreporter.write_sep("-", "verdicts by what they rest on (cia / manual / inferred)")
        for line in by_basis:
            terminalreporter.write_line(f"  {line}")
    if warnings:
        terminalreporter.write_sep("-", "warnings: rules we only inferred were broken (fail them with "
                                        "--strict)", yellow=True)
        for line in warnings:
            terminalreporter.write_line(line, yellow=True)
    if run_lines:
        terminalreporter.write_sep("-", "the device on the bench")
        for text, alarm in run_lines:
            terminalreporter.write_line(text, red=alarm, bold=alarm)
    budget_line = time_budget.terminal_line(config)
    if budget_line:
        terminalreporter.write_line(budget_line)
    _skips_by_reason(terminalreporter, terminalreporter.stats.get("skipped", []))
    deviations = deviations_relied_on(config)
    if deviations:
        terminalreporter.write_sep("-", "documented deviations relied on")
        for quirk_id, count in sorted(deviations.items()):
            terminalreporter.write_line(f"{count:4d}  {quirk_id}")
    terminalreporter.write_sep("-", f"reports in {config.stash[REPORT_DIR]}")


def _skips_by_reason(terminalreporter: pytest.TerminalReporter, skipped: list[pytest.TestReport]) -> None:
    """The checks that gave no verdict, by reason: first those in scope (not testable: the verdict is INCOMPLETE;
    inconclusive: at most PASS WITH WARNINGS), then the run's scope (not applicable, not available, not selected)."""
    in_scope: Counter[str] = Counter()
    scope: Counter[str] = Counter()
    for rep in skipped:
        kind, _ = booked(rep)
        key = skip_reason_key(skip_reason(rep))
        (in_scope if kind is None or kind.in_scope else scope)[key] += 1
    if in_scope:
        terminalreporter.write_sep("-", "in scope but not judged (not testable: INCOMPLETE; inconclusive: host late)",
                                   red=True)
        for reason, count in in_scope.most_common():
            terminalreporter.write_line(f"{count:4d}  {reason}", red=True)
    if scope:
        terminalreporter.write_sep("-", "out of scope: not applicable, not available, not selected (not counted)")
        for reason, count in scope.most_common():
            terminalreporter.write_line(f"{count:4d}  {reason}")


def fail_all_skipped(session: pytest.Session) -> None:
    """A run where every test was skipped is not green (labgrid #610)."""
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is None or REPORT_DIR not in session.config.stash or session.config.option.collectonly:
        return
    stats = reporter.stats
    ran = len(stats.get("passed", [])) + len(stats.get("failed", [])) + len(stats.get("error", []))
    if session.testscollected and not ran:
        held = [rep for rep in stats.get("skipped", []) if booked(rep)[0] is Kind.NOT_TESTABLE]
        if held:  # the device's state kept the checks from running: INCOMPLETE (exit 6), not a failure
            reporter.write_line(f"every test was skipped, {len(held)} of them not testable: the run is INCOMPLETE",
                                red=True)
            return
        reporter.write_line("every test was skipped: nothing was checked, so the run fails", red=True)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
