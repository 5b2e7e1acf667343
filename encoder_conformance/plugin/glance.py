"""The report's first screen, read at a glance: what a QA bench needs before it scrolls.

In this order: the overall verdict as a coloured banner (profile, date, serial), the device's identity, the
verdict per area with its counts, the failures (expected vs observed, the clause or manual section they rest
on, links to the frame trace), the internal errors of the tool (outside every verdict), the warnings (rules
we only inferred). Below, folded: device custody (its
alarms stay unfolded when the device was not given back), verdicts by basis, the profile's documented
deviations, skips by reason, settings with their sources.

A pure function of a RunSummary (plus what the summary does not hold: custody lines, the profile's
deviations, the environment) to an HTML fragment with its own small inline CSS, so that it is tested
without pytest and can be reused by other pages (a certificate, the history). The markup is the Jinja2
template ``glance.html.j2`` beside this module (autoescaped: names, messages and settings are text, never
markup); this module gathers what it shows.
"""

from __future__ import annotations

import functools
from collections import Counter
from dataclasses import dataclass, field
from importlib import resources
from pathlib import PurePosixPath
from typing import TYPE_CHECKING

from encoder_conformance.coverage import Kind
from encoder_conformance.run_summary import AREAS, INTERNAL_ERROR_TEXT, RunSummary, TestResult

if TYPE_CHECKING:
    import jinja2

#: the template of the first screen, package data beside this module
TEMPLATE = "glance.html.j2"

#: the banner's colour per overall verdict
VERDICT_CLASS = {"PASS": "pass", "FAIL": "fail", "PASS WITH WARNINGS": "warn", "INCOMPLETE": "inc",
                 "COULD NOT TEST": "none", "INTERNAL ERROR": "int", "NOT RUN": "none"}

KIND_NAMES = {"run": "conformance run", "accept": "acceptance check"}

#: identity keys (as the dut fixture records them) in the order a reader looks for them, with short labels
IDENTITY_ORDER = (("serial number (1018h.4)", "serial (1018h.4)"), ("revision (1018h.3)", "revision (1018h.3)"),
                  ("vendor-id (1018h.1)", "vendor (1018h.1)"), ("product code (1018h.2)", "product (1018h.2)"),
                  ("device name (1008h)", "name (1008h)"), ("device type (1000h)", "device type (1000h)"))

#: the counts per area, in the table's column order
AREA_COLUMNS = ("passed", "failed", "warnings", "not testable", "inconclusive", "out of scope")

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
    ran = {area.area: area for area in summary.areas()}
    held = summary.with_kind(Kind.NOT_TESTABLE, Kind.INCONCLUSIVE)
    scope = summary.with_kind(Kind.NOT_APPLICABLE, Kind.NOT_EQUIPPED, Kind.NOT_SELECTED)
    return _template().render(
        s=summary, context=context, kind_name=KIND_NAMES.get(summary.kind, summary.kind), figures=_figures(summary),
        internal_error_text=INTERNAL_ERROR_TEXT, identity=_identity(summary), area_columns=AREA_COLUMNS,
        areas=[(name, ran.get(name)) for name in [*AREAS, *(a for a in ran if a not in AREAS)]
               if name in ran or name != "other"],
        failed=summary.with_outcome("failed"), warned=summary.with_outcome("warning"),
        custody_alarms_shown=summary.device_restored is not True or bool(summary.device_memory),
        custody_state=_custody_state(summary), by_basis=_by_basis(summary),
        relied=sum(1 for d in context.deviations if d.relied_on),
        not_judged=_SkipTable.of(held), out_of_scope=_SkipTable.of(scope), budget=summary.time_budget,
        settings=_settings(summary, context.environment))


def skip_reason_key(reason: str) -> str:
    """Skips grouped by reason: the text before its first parenthesis (which names the parameter or object)."""
    return reason.split(" (")[0]


@functools.cache
def _template() -> jinja2.Template:
    """glance.html.j2 (package data), autoescaped; its lines stripped and joined (see the template's head).
    Jinja2 is imported here, at the end of a run, not when the plugin loads. Compiling the template costs
    15-40 ms; Jinja2's bytecode cache (a private folder of the user's in the temporary directory, keyed by the
    source's checksum) keeps the compiled code for the next run, where one is possible."""
    import jinja2

    path = resources.files(__package__).joinpath(TEMPLATE)
    source = "".join(line.strip() for line in path.read_text(encoding="utf-8").splitlines())
    try:
        cache: jinja2.BytecodeCache | None = jinja2.FileSystemBytecodeCache()
    except (OSError, RuntimeError):  # no private folder of ours in the temporary directory
        cache = None
    env = jinja2.Environment(autoescape=True, undefined=jinja2.StrictUndefined, bytecode_cache=cache,
                             loader=jinja2.FunctionLoader(lambda name: (source, str(path), lambda: True)))
    env.globals.update(css=lambda verdict: VERDICT_CLASS.get(verdict, "none"),
                       log_of=lambda trace: str(PurePosixPath(trace).with_suffix(".log")))
    return env.get_template(TEMPLATE)


def _figures(summary: RunSummary) -> str:
    counts: Counter[str] = Counter(r.outcome for r in summary.results)
    return ", ".join(f"{counts[key]} {label if counts[key] > 1 else label.removesuffix('s')}"
                     for key, label in (("passed", "passed"), ("failed", "failed"), ("error", "internal errors"),
                                        ("warning", "warnings"), ("skipped", "without a verdict")) if counts[key])


def _identity(summary: RunSummary) -> list[tuple[str, str]]:
    """The identity's (label, value) pairs: the known keys in reading order, then the others."""
    known = [(label, summary.identity[key]) for key, label in IDENTITY_ORDER if key in summary.identity]
    names = {key for key, _ in IDENTITY_ORDER}
    return known + [(key, value) for key, value in summary.identity.items() if key not in names]


def _custody_state(summary: RunSummary) -> str:
    if summary.device_memory:
        return "values given back, memory NOT as found"
    return {True: "given back as found", False: "NOT given back as found", None: "no restore recorded"}[
        summary.device_restored]


def _by_basis(summary: RunSummary) -> list[tuple[str, str]]:
    """(basis, "n outcome, ...") per verdict basis, sorted."""
    counts = Counter((r.basis, r.outcome) for r in summary.results if r.basis)
    return [(basis, ", ".join(f"{n} {outcome}" for (b, outcome), n in sorted(counts.items()) if b == basis))
            for basis in sorted({b for b, _ in counts})]


@dataclass(frozen=True)
class _SkipTable:
    """Results without a verdict grouped by reason, the largest group first."""

    count: int
    groups: list[tuple[str, list[str]]]

    @classmethod
    def of(cls, results: list[TestResult]) -> _SkipTable:
        groups: dict[str, list[str]] = {}
        for result in results:
            groups.setdefault(skip_reason_key(result.message or "no reason given"), []).append(result.nodeid)
        return cls(len(results), sorted(groups.items(), key=lambda kv: (-len(kv[1]), kv[0])))


def _settings(summary: RunSummary, environment: dict[str, str]) -> list[tuple[str, object]]:
    rows: list[tuple[str, object]] = [
        ("station", summary.station or "-"), ("operator", summary.operator or "-"),
        ("profile sha256", summary.profile_sha256), *summary.settings.items(), *environment.items()]
    if summary.report_dir:
        rows.append(("report folder", summary.report_dir))
    return rows
