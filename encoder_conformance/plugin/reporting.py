"""Report outputs: where they go, the header (identity, profile, bus), per-test evidence, summaries."""

from __future__ import annotations

import base64
import html
import time
from pathlib import Path

import pytest

from ..paths import REPO_ROOT, SUITES_DIR
from .allure_writer import BackgroundWriter, write_in_background
from .evidence import EVIDENCE
from .options import bench_settings, settings_of
from .verdicts import add_property, html_section, terminal_lines
from .verdicts import strict as verdicts_strict

REPORT_DIR = pytest.StashKey[Path]()
ALLURE_WRITER = pytest.StashKey[BackgroundWriter]()
IDENTITY = pytest.StashKey[dict[str, str]]()


def runs_suites(config: pytest.Config) -> bool:
    """True when this pytest run includes the conformance suites (not only the self-tests)."""
    suites = SUITES_DIR
    paths = [Path(a.split("::")[0]).resolve() for a in config.args] or [suites]
    return any(p == suites or suites in p.parents for p in paths)


def configure_outputs(config: pytest.Config) -> None:
    """Conformance runs write report.html, junit.xml and allure-results into one folder."""
    if not runs_suites(config) or hasattr(config, "workerinput"):
        return
    settings = settings_of(config)
    given = config.getoption("--report-dir")
    stamp = time.strftime("%Y%m%d-%H%M%S")
    station_reports = settings.station.reports if settings.station is not None else None
    parent = station_reports or REPO_ROOT / "reports"
    folder = Path(given) if given else parent / f"{stamp}-{settings.loaded.profile.id}"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "traces").mkdir(exist_ok=True)
    config.stash[REPORT_DIR] = folder
    option = config.option
    if not getattr(option, "htmlpath", None):
        option.htmlpath = str(folder / "report.html")
        option.self_contained_html = True
    if not getattr(option, "xmlpath", None):
        option.xmlpath = str(folder / "junit.xml")
    if config.getoption("--allure") and not getattr(option, "allure_report_dir", None):
        option.allure_report_dir = str(folder / "allure-results")
        option.clean_alluredir = True


def start_background_writers(config: pytest.Config) -> None:
    """Allure's result files are written off the test thread (see allure_writer)."""
    if report_dir(config) is not None and (writer := write_in_background()) is not None:
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
    data["SDO abort codes"] = f"{config.getoption('--abort-codes')} (--abort-codes)"
    data["Inferred rules"] = "failures (--strict-inferred)" if verdicts_strict(config) else "warnings"
    data["Run kind"] = config.getoption("--run-kind", default="run")
    bench = bench_settings(settings, config.getoption("--station"), config.getoption("--shaft-drive"))
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
        f"verdicts: SDO abort codes {config.getoption('--abort-codes')} (--abort-codes); rules we inferred judged as "
        f"{'failures (--strict-inferred)' if verdicts_strict(config) else 'warnings (--strict-inferred fails them)'}",
    ]
    if settings.shaft_drive is not None:
        lines.append(f"shaft drive: {settings.shaft_drive.spec} (--shaft-drive)")
    folder = report_dir(config)
    if folder:
        lines.append(f"reports: {folder}")
    return lines


def attach_evidence(item: pytest.Item, call: pytest.CallInfo[None], report: pytest.TestReport) -> None:
    """Add measurements, deviations and the trace link to the HTML report and the allure result."""
    evidence = item.stash.get(EVIDENCE, None)
    if evidence is None or report.when != "call":
        return
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
    # an acceptance plots only what failed: rendering a plot costs ~1.5 s (matplotlib), a third of its budget
    plot = report.outcome != "passed" or item.config.getoption("--run-kind", default="run") != "accept"
    for timing in evidence.timings:  # statistics and plot, one per timing measurement
        image = base64.b64encode(timing.png()).decode("ascii") if plot else None
        extras.append(html_extras.html(f"<div class='timing'>{timing.html_table()}" + (
            f"<img src='data:image/png;base64,{image}' alt='{html.escape(timing.name)}'>" if image else "")
            + "</div>"))
        for name, value in timing.properties():
            add_property(item, report, name, value)
    folder = report_dir(item.config)
    if evidence.trace_path and evidence.trace_path.exists() and folder:
        relative = evidence.trace_path.relative_to(folder).as_posix()
        extras.append(html_extras.url(relative, name="bus trace (ASC)"))
    report.extras = extras
    for quirk_id, _ in evidence.deviations:
        add_property(item, report, "documented_deviation", quirk_id)


def html_summary(prefix: list[str], session: pytest.Session, run_lines: list[tuple[str, bool]]) -> None:
    """Run outcome and device custody (alarms in red), the identity read, the documented deviations."""
    config = session.config
    profile = settings_of(config).loaded.profile
    if profile.todo:
        items = "".join(f"<li>{html.escape(todo)}</li>" for todo in profile.todo)
        prefix.append(f"<h2 style='color:#b60'>{html.escape(draft_banner(profile))}</h2>"
                      f"<details><summary>the assumptions (todo: in the profile)</summary><ol>{items}</ol></details>")
    prefix.append(html_section(config))
    if run_lines:
        items = "".join(
            f"<li style='color:{'#c00;font-weight:bold' if alarm else 'inherit'}'>{html.escape(text)}</li>"
            for text, alarm in run_lines
        )
        prefix.append(f"<h2>The device on the bench: snapshot and restore</h2><ul>{items}</ul>")
    settings = settings_of(config)
    profile = settings.loaded.profile
    identity = config.stash.get(IDENTITY, {})
    rows = "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>" for k, v in identity.items())
    rows = rows or "<tr><td>not read</td></tr>"
    prefix.append(f"<h2>Device identity (read from the device)</h2><table>{rows}</table>")
    quirk_rows = "".join(
        f"<tr><td>{html.escape(qid)}</td><td>{html.escape(q.title)}</td><td>{html.escape(q.manual)}</td>"
        f"<td>{html.escape(q.deviates_from or '')}</td></tr>"
        for qid, q in profile.quirks.items()
    )
    prefix.append(
        f"<h2>Documented deviations of {html.escape(profile.id)} ({len(profile.quirks)})</h2>"
        "<table><tr><th>id</th><th>deviation</th><th>manual</th><th>deviates from</th></tr>"
        f"{quirk_rows}</table>"
    )


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
                                        "--strict-inferred)", yellow=True)
        for line in warnings:
            terminalreporter.write_line(line, yellow=True)
    if run_lines:
        terminalreporter.write_sep("-", "the device on the bench")
        for text, alarm in run_lines:
            terminalreporter.write_line(text, red=alarm, bold=alarm)
    stats = terminalreporter.stats
    skipped = stats.get("skipped", [])
    if skipped:
        reasons: dict[str, int] = {}
        for rep in skipped:
            reason = rep.longrepr[2] if isinstance(rep.longrepr, tuple) else str(rep.longrepr)
            key = reason.replace("Skipped: ", "").split(" (")[0]
            reasons[key] = reasons.get(key, 0) + 1
        terminalreporter.write_sep("-", "skipped, by reason")
        for reason, count in sorted(reasons.items(), key=lambda kv: -kv[1]):
            terminalreporter.write_line(f"{count:4d}  {reason}")
    deviations: dict[str, int] = {}
    for rep in stats.get("passed", []) + stats.get("failed", []):
        for key, value in rep.user_properties:
            if key == "documented_deviation":
                deviations[value] = deviations.get(value, 0) + 1
    if deviations:
        terminalreporter.write_sep("-", "documented deviations relied on")
        for quirk_id, count in sorted(deviations.items()):
            terminalreporter.write_line(f"{count:4d}  {quirk_id}")
    terminalreporter.write_sep("-", f"reports in {config.stash[REPORT_DIR]}")


def fail_all_skipped(session: pytest.Session) -> None:
    """A run where every test was skipped is not green (labgrid #610)."""
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is None or REPORT_DIR not in session.config.stash or session.config.option.collectonly:
        return
    stats = reporter.stats
    ran = len(stats.get("passed", [])) + len(stats.get("failed", [])) + len(stats.get("error", []))
    if session.testscollected and not ran:
        reporter.write_line("every test was skipped: nothing was checked, so the run fails", red=True)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
