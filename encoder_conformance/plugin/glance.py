"""The report's first screen, read at a glance: what a QA bench needs before it scrolls.

In this order: the overall verdict as a coloured banner (profile, date, serial), the device's identity, the
verdict per area with its counts, the failures (expected vs observed, the clause or manual section they rest
on, links to the frame trace), the internal errors of the tool (outside every verdict), the warnings (rules
we only inferred). Below, folded: device custody (its
alarms stay unfolded when the device was not given back), verdicts by basis, the profile's documented
deviations, skips by reason, settings with their sources.

A pure function of a RunSummary (plus what the summary does not hold: custody lines, the profile's
deviations, the environment) to an HTML fragment with its own small inline CSS, so that it is tested
without pytest and can be reused by other pages (a certificate, the history).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from html import escape
from pathlib import PurePosixPath

from encoder_conformance.coverage import Kind
from encoder_conformance.run_summary import AREAS, INTERNAL_ERROR_TEXT, RunSummary, TestResult

#: the banner's colour per overall verdict
VERDICT_CLASS = {"PASS": "pass", "FAIL": "fail", "PASS WITH WARNINGS": "warn", "INCOMPLETE": "inc",
                 "COULD NOT TEST": "none", "INTERNAL ERROR": "int", "NOT RUN": "none"}

KIND_NAMES = {"run": "conformance run", "accept": "acceptance check"}

#: identity keys (as the dut fixture records them) in the order a reader looks for them, with short labels
IDENTITY_ORDER = (("serial number (1018h.4)", "serial (1018h.4)"), ("revision (1018h.3)", "revision (1018h.3)"),
                  ("vendor-id (1018h.1)", "vendor (1018h.1)"), ("product code (1018h.2)", "product (1018h.2)"),
                  ("device name (1008h)", "name (1008h)"), ("device type (1000h)", "device type (1000h)"))

CSS = """<style>
.glance{font-family:Helvetica,Arial,sans-serif;font-size:13px;max-width:1300px;color:#222}
.glance a{color:#1558b0}
.glance h2{font-size:16px;margin:14px 0 4px}
.glance table{border-collapse:collapse;margin:2px 0}
.glance th,.glance td{border:1px solid #ccc;padding:2px 8px;text-align:left;vertical-align:top}
.glance th{background:#f3f3f3;font-weight:600}
.glance td.n{text-align:right;font-variant-numeric:tabular-nums}
.g-banner{padding:10px 16px;border-radius:4px;color:#fff;margin:4px 0 8px}
.g-banner .g-word{font-size:30px;font-weight:bold;margin-right:18px}
.g-int{background:#6a1b9a}.g-item.g-i{border-left-color:#6a1b9a}
.g-pass{background:#1e7e34}.g-fail{background:#c62828}.g-warn{background:#e69500}.g-none{background:#757575}
.g-inc{background:#ad4e00}
.glance .g-v-pass{color:#1e7e34;font-weight:bold}.glance .g-v-fail{color:#c62828;font-weight:bold}
.glance .g-v-warn{color:#b36b00;font-weight:bold}.glance .g-v-none{color:#888}
.g-draft{background:#fff3cd;border:1px solid #e0b000;padding:4px 10px;margin:4px 0}
.g-alarm{background:#fdecea;border:1px solid #c62828;color:#c62828;font-weight:bold;padding:4px 10px;margin:4px 0}
.g-item{border-left:4px solid #c62828;padding:2px 8px;margin:6px 0}
.g-item.g-w{border-left-color:#e69500}
.g-item pre{white-space:pre-wrap;margin:2px 0;max-height:10em;overflow:auto;background:#fafafa}
.glance details{margin:4px 0}.glance summary{cursor:pointer;font-weight:600}
.g-small{color:#555;font-size:12px}
</style>"""


@dataclass(frozen=True)
class Deviation:
    """One documented deviation of the profile (a quirk) and how many verdicts of this run relied on it."""

    quirk_id: str
    title: str
    manual: str
    deviates_from: str = ""
    relied_on: int = 0


@dataclass
class PageContext:
    """What the first screen shows that a RunSummary does not hold."""

    custody: list[tuple[str, bool]] = field(default_factory=list)  # (line, alarm) from lifecycle.summary_lines
    deviations: list[Deviation] = field(default_factory=list)
    draft: str | None = None  # the draft-profile banner, when the profile has todo: items
    todo: list[str] = field(default_factory=list)
    environment: dict[str, str] = field(default_factory=dict)  # pytest-html's environment table, folded here
    inferred_mode: str = "warnings"  # how rules we only inferred were judged


def render(summary: RunSummary, context: PageContext | None = None) -> str:
    """The first screen as one HTML fragment (its CSS included)."""
    context = context or PageContext()
    parts = [CSS, "<div class='glance'>", _banner(summary)]
    if context.draft:
        items = "".join(f"<li>{escape(t)}</li>" for t in context.todo)
        parts.append(f"<div class='g-draft'><b>{escape(context.draft)}</b>"
                     f"<details><summary>the assumptions (todo: in the profile)</summary><ol>{items}</ol></details>"
                     "</div>")
    parts += [_identity(summary), _areas(summary), _failures(summary), _internal_errors(summary), _warnings(summary),
              _custody(summary, context.custody), _by_basis(summary, context.inferred_mode),
              _deviations(summary, context.deviations), _skips(summary), _time_budget(summary),
              _settings(summary, context.environment), "</div>"]
    return "".join(parts)


def skip_reason_key(reason: str) -> str:
    """Skips grouped by reason: the text before its first parenthesis (which names the parameter or object)."""
    return reason.split(" (")[0]


def _banner(summary: RunSummary) -> str:
    verdict = summary.overall
    counts: Counter[str] = Counter(r.outcome for r in summary.results)
    figures = ", ".join(f"{counts[key]} {label if counts[key] > 1 else label.removesuffix('s')}"
                        for key, label in (("passed", "passed"), ("failed", "failed"), ("error", "internal errors"),
                                           ("warning", "warnings"), ("skipped", "without a verdict")) if counts[key])
    serial = f" &middot; serial {escape(summary.serial)}" if summary.serial else ""
    duration = f", {summary.duration_s:.0f} s" if summary.duration_s else ""
    why = f"<div>could not test: {escape(summary.could_not_test)}</div>" if summary.could_not_test else ""
    if summary.device_failed:
        why += f"<div>the run stopped: {escape(summary.device_failed)}; {summary.not_run} test(s) not run</div>"
    if summary.internal_errors:
        why += (f"<div>{len(summary.internal_errors)} {INTERNAL_ERROR_TEXT} (outside every verdict: see "
                "<a href='#internal-errors' style='color:#fff'>below</a>)</div>")
    if summary.device_restored is False:
        why += "<div>the device was NOT given back as found: see the custody lines below</div>"
    return (f"<div class='g-banner g-{VERDICT_CLASS.get(verdict, 'none')}' id='verdict'>"
            f"<span class='g-word'>{escape(verdict)}</span>"
            f"profile <b>{escape(summary.profile_id)}</b> &middot; {escape(summary.started.replace('T', ' '))}"
            f"{serial} &middot; {escape(KIND_NAMES.get(summary.kind, summary.kind))}{duration}"
            f"<div>{figures or 'no test ran'}</div>{why}</div>")


def _identity(summary: RunSummary) -> str:
    if not summary.identity:
        return "<h2>Device identity</h2><p>not read from the device</p>"
    known = [(label, summary.identity[key]) for key, label in IDENTITY_ORDER if key in summary.identity]
    names = {key for key, _ in IDENTITY_ORDER}
    known += [(key, value) for key, value in summary.identity.items() if key not in names]
    head = "".join(f"<th>{escape(label)}</th>" for label, _ in known)
    cells = "".join(f"<td>{escape(value)}</td>" for _, value in known)
    return (f"<h2>Device identity (read from the device)</h2>"
            f"<table id='identity'><tr>{head}</tr><tr>{cells}</tr></table>")


def _verdict_cell(verdict: str) -> str:
    return f"<td class='g-v-{VERDICT_CLASS.get(verdict, 'none')}'>{escape(verdict)}</td>"


def _areas(summary: RunSummary) -> str:
    ran = {area.area: area for area in summary.areas()}
    rows = []
    columns = ("passed", "failed", "warnings", "not testable", "inconclusive", "out of scope")
    for name in [*AREAS, *(a for a in ran if a not in AREAS)]:
        area = ran.get(name)
        if area is None:
            if name != "other":
                zeros = "<td class='n'>0</td>" * len(columns)
                rows.append(f"<tr><td>{escape(name)}</td><td class='g-v-none'>NOT RUN</td>{zeros}</tr>")
            continue
        counts = "".join(f"<td class='n'>{n}</td>" for n in (area.passed, area.failed, area.warnings,
                                                            area.not_testable, area.inconclusive, area.out_of_scope))
        rows.append(f"<tr><td>{escape(name)}</td>{_verdict_cell(area.verdict)}{counts}</tr>")
    heads = "".join(f"<th>{c}</th>" for c in columns)
    return (f"<h2>Verdict per area</h2><table id='areas'><tr><th>area</th><th>verdict</th>{heads}</tr>"
            f"{''.join(rows)}</table>{_scope(summary)}")


def _scope(summary: RunSummary) -> str:
    """The run's scope as declared before the first test: what the station and the options left out."""
    if not summary.scope and not summary.deselected:
        return ""
    rows = "".join(f"<tr><td>{escape(k)}</td><td>{escape(v)}</td></tr>" for k, v in summary.scope.items())
    if summary.deselected:
        rows += f"<tr><td>deselected</td><td>{summary.deselected} test(s) left out by the selection</td></tr>"
    return ("<div class='g-small'>Scope of this run (checks outside it are listed, never counted): </div>"
            f"<table id='scope'>{rows}</table>")


def trace_links(trace: str | None) -> str:
    """Links to a test's frame trace: the ASC file and the candump log written beside it."""
    if not trace:
        return "no trace kept"
    path = PurePosixPath(trace)
    return (f"<a href='{escape(trace)}'>trace (ASC)</a> &middot; "
            f"<a href='{escape(str(path.with_suffix('.log')))}'>trace (candump log)</a>")


def _item(result: TestResult, css: str) -> str:
    rests_on = " &middot; ".join(escape(x) for x in (result.basis, result.source) if x) or "not recorded"
    return (f"<div class='g-item {css}'><b>{escape(result.nodeid)}</b> <span class='g-small'>[{escape(result.area)}, "
            f"{escape(result.outcome)}]</span><pre>{escape(result.message or '(no message)')}</pre>"
            f"<div class='g-small'>rests on: {rests_on} &middot; {trace_links(result.trace)}</div></div>")


def _failures(summary: RunSummary) -> str:
    failed = summary.with_outcome("failed")
    if not failed:
        return "<h2 id='failures'>Failures: none</h2>"
    return f"<h2 id='failures'>Failures ({len(failed)})</h2>" + "".join(_item(r, "") for r in failed)


def _internal_errors(summary: RunSummary) -> str:
    errors = summary.internal_errors
    if not errors:
        return ""
    return (f"<h2 id='internal-errors'>Internal errors of the tool ({len(errors)}): please report them</h2>"
            "<p class='g-small'>not findings about the device: counted in no area and no verdict</p>"
            + "".join(_item(r, "g-i") for r in errors))


def _warnings(summary: RunSummary) -> str:
    warned = summary.with_outcome("warning")
    if not warned:
        return ""
    return (f"<h2 id='warnings'>Warnings: rules we only inferred were broken ({len(warned)})</h2>"
            + "".join(_item(r, "g-w") for r in warned))


def _custody(summary: RunSummary, lines: list[tuple[str, bool]]) -> str:
    if not lines:
        return ""
    items = "".join(f"<li{' class=g-alarm' if alarm else ''}>{escape(text)}</li>" for text, alarm in lines)
    alarms = [text for text, alarm in lines if alarm]
    visible = ""
    if alarms and summary.device_restored is not True:  # never fold what the operator must act on
        visible = "".join(f"<div class='g-alarm'>{escape(text)}</div>" for text in alarms)
    state = {True: "given back as found", False: "NOT given back as found", None: "no restore recorded"}
    return (f"{visible}<details id='custody'><summary>The device on the bench: snapshot and restore "
            f"({state[summary.device_restored]})</summary><ul>{items}</ul></details>")


def _by_basis(summary: RunSummary, mode: str) -> str:
    counts = Counter((r.basis, r.outcome) for r in summary.results if r.basis)
    lines = []
    for basis in sorted({b for b, _ in counts}):
        parts = ", ".join(f"{n} {outcome}" for (b, outcome), n in sorted(counts.items()) if b == basis)
        lines.append(f"<li>{escape(basis)}: {escape(parts)}</li>")
    return ("<details id='by-basis'><summary>Verdicts by what they rest on</summary><p>cia: a CiA clause; manual: "
            f"the device's manual; inferred: our reading where neither says (judged as {escape(mode)})</p>"
            f"<ul>{''.join(lines) or '<li>no verdicts</li>'}</ul></details>")


def _deviations(summary: RunSummary, deviations: list[Deviation]) -> str:
    if not deviations:
        return ""
    relied = sum(1 for d in deviations if d.relied_on)
    rows = "".join(f"<tr><td>{escape(d.quirk_id)}</td><td class='n'>{d.relied_on or ''}</td><td>{escape(d.title)}</td>"
                   f"<td>{escape(d.manual)}</td><td>{escape(d.deviates_from)}</td></tr>" for d in deviations)
    return (f"<details id='deviations'><summary>Documented deviations of {escape(summary.profile_id)} "
            f"({len(deviations)}; {relied} relied on by this run's verdicts)</summary><table><tr><th>id</th>"
            "<th>verdicts relying on it</th><th>deviation</th><th>manual</th><th>deviates from</th></tr>"
            f"{rows}</table></details>")


def _skip_table(results: list[TestResult], title: str, anchor: str, open_: bool) -> str:
    if not results:
        return ""
    groups: dict[str, list[str]] = {}
    for result in results:
        groups.setdefault(skip_reason_key(result.message or "no reason given"), []).append(result.nodeid)
    rows = "".join(
        f"<tr><td class='n'>{len(tests)}</td><td>{escape(reason)}<div class='g-small'>"
        f"{'<br>'.join(escape(t) for t in tests)}</div></td></tr>"
        for reason, tests in sorted(groups.items(), key=lambda kv: (-len(kv[1]), kv[0])))
    return (f"<details id='{anchor}'{' open' if open_ else ''}><summary>{title}: {len(results)} tests, "
            f"{len(groups)} reasons</summary><table><tr><th>tests</th><th>reason</th></tr>{rows}</table></details>")


def _skips(summary: RunSummary) -> str:
    """Checks in scope that did not judge (open: they make the verdict INCOMPLETE), then the run's scope."""
    held = summary.with_kind(Kind.NOT_TESTABLE, Kind.INCONCLUSIVE)
    scope = summary.with_kind(Kind.NOT_APPLICABLE, Kind.NOT_EQUIPPED, Kind.NOT_SELECTED)
    return (_skip_table(held, "In scope but not judged (not testable: INCOMPLETE; inconclusive: the host was late)",
                        "not-judged", True)
            + _skip_table(scope, "Out of scope (not applicable, not available, not selected)", "skips", False))


def _settings(summary: RunSummary, environment: dict[str, str]) -> str:
    rows = [("station", summary.station or "-"), ("operator", summary.operator or "-"),
            ("profile sha256", summary.profile_sha256), *summary.settings.items(), *environment.items()]
    if summary.report_dir:
        rows.append(("report folder", summary.report_dir))
    body = "".join(f"<tr><th>{escape(k)}</th><td>{escape(str(v))}</td></tr>" for k, v in rows)
    return (f"<details id='settings'><summary>Settings with their sources, environment</summary>"
            f"<table>{body}</table></details>")


def _time_budget(summary: RunSummary) -> str:
    """Where the run's time went: owed to the device per kind of wait, the tester's share, per area, the
    costliest tests and why."""
    budget = summary.time_budget
    if not budget:
        return ""
    owed = "".join(f"<tr><th>{escape(name)}</th><td class='n'>{seconds:.2f} s</td></tr>"
                   for name, seconds in sorted(budget["owed"].items(), key=lambda item: -item[1]))
    areas = "".join(f"<tr><th>{escape(name)}</th><td class='n'>{a['tests']:.0f}</td><td class='n'>{a['seconds']:.2f} s"
                    f"</td><td class='n'>{a['owed']:.2f} s</td></tr>"
                    for name, a in sorted(budget["areas"].items(), key=lambda item: -item[1]["seconds"]))
    costly = "".join(f"<tr><td>{escape(t['nodeid'])}</td><td class='n'>{t['seconds']:.2f} s</td>"
                     f"<td>{escape(t['why'])}</td></tr>" for t in budget["costliest"])
    share = budget.get("tester_share") or 0
    return (f"<details id='time-budget'><summary>Time budget: {budget['wall_s']:.1f} s, owed to the device "
            f"{budget['owed_s']:.1f} s, tester {budget['tester_s']:.1f} s ({100 * share:.0f} %)</summary>"
            f"<p>Owed: every wait for the device, booked to what it waits for. Tester: the rest (start-up, "
            f"collection and reports {budget['outside_tests_s']:.2f} s; median per test "
            f"{budget['tester_per_test_median_ms']} ms).</p><table>{owed}</table>"
            f"<table><tr><th>area</th><th>tests</th><th>seconds</th><th>owed</th></tr>{areas}</table>"
            f"<table><tr><th>the costliest tests</th><th>seconds</th><th>why</th></tr>{costly}</table></details>")
