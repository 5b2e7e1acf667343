"""``encoder-conformance accept``: the goods-in check of one delivered encoder against the profile bought.

Runs the acceptance selection (plugin/acceptance.py) in-process like ``run``, recorded as kind
``accept`` in run-summary.json, and prints one line per area with its verdict, the overall verdict and
the report folder. Exit codes follow exit_codes.RunExit (0 pass, also with warnings; 1 fail; 69 could
not test; 70 not restored). pytest's own terminal output is off unless ``--verbose``: a goods-in operator
reads the verdict, the report holds the detail.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from encoder_conformance.cli.usage import command_arguments
from encoder_conformance.coverage import Kind
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.plugin import option_table
from encoder_conformance.run_summary import RunSummary

BusArguments = Callable[..., None]
MESSAGE_WIDTH = 110  # characters of a failure shown under its area


class _SummaryCatcher:
    """A pytest plugin that keeps the run's summary for the verdict lines (the report folder may be stamped)."""

    def __init__(self) -> None:
        self.summary: RunSummary | None = None

    def pytest_unconfigure(self, config) -> None:  # noqa: ANN001 - pytest.Config
        from encoder_conformance.plugin.run_record import summary_of

        self.summary = summary_of(config)


def _pytest_argv(args: argparse.Namespace) -> list[str]:
    from encoder_conformance.plugin.acceptance import KIND, KIND_OPTION, pytest_args

    # --assert=plain: the suites' assertions carry their own messages, and rewriting ~120 modules costs ~2 s
    # where no bytecode cache is written (PYTHONDONTWRITEBYTECODE)
    argv = [*pytest_args(), KIND_OPTION, KIND, "-p", "no:cacheprovider", *option_table.unused_plugins([]),
            "--assert=plain", *option_table.pytest_argv("accept", vars(args))]
    if not args.verbose:
        argv += ["-p", "no:terminal"]
    return argv


def format_verdict(summary: RunSummary) -> list[str]:
    """One line per area, the first failure under a failed area, the overall verdict and the report folder."""
    identity = summary.identity
    lines = [f"accept {summary.profile_id}: serial {summary.serial or '-'}, revision {summary.revision or '-'}"
             + (f", device name {identity['device name (1008h)']}" if identity.get("device name (1008h)") else "")]
    for area in summary.areas():
        counts = ", ".join(f"{n} {what}" for n, what in (
            (area.passed, "passed"), (area.failed, "failed"), (area.warnings, "warnings"),
            (area.not_testable, "not testable"), (area.inconclusive, "inconclusive"),
            (area.out_of_scope, "out of scope")) if n)
        lines.append(f"  {area.area:18s} {area.verdict:18s} ({counts})")
        if area.verdict == "FAIL":
            failed = next(r for r in summary.results if r.area == area.area and r.outcome in ("failed", "error"))
            first = (failed.message.strip().splitlines() or [""])[0].removeprefix("AssertionError: ")
            lines.append(f"      {failed.nodeid.split('/')[-1]}: {first[:MESSAGE_WIDTH]}")
    for held in summary.with_kind(Kind.NOT_TESTABLE)[:3]:
        lines.append(f"      {held.nodeid.split('/')[-1]}: {held.message.splitlines()[0][:MESSAGE_WIDTH]}")
    if summary.could_not_test:
        lines.append(f"  could not test: {summary.could_not_test}")
    if summary.device_restored is False:
        lines.append("  the device was NOT restored as found: see the report, then 'encoder-conformance restore "
                     "--from'")
    lines.append(f"{summary.overall} ({summary.duration_s:.1f} s); report: {summary.report_dir}")

    return lines


def exit_code(summary: RunSummary | None, status: int) -> int:
    """pytest's status as ``run`` gives it, except that an acceptance which checked nothing fails."""
    if summary is not None and summary.overall == "NOT RUN" and status == RunExit.PASSED:
        return RunExit.NON_CONFORMANT
    return status


def _cmd_accept(args: argparse.Namespace, extra: list[str]) -> int:
    if len(args.station) > 1:  # one device per station, in parallel: one accept process each
        from encoder_conformance.runs.stations import run_stations

        return run_stations(args.command, args.station, args.argv, args.report_dir)
    import pytest

    catcher = _SummaryCatcher()
    status = int(pytest.main(_pytest_argv(args), plugins=[catcher]))
    if status == pytest.ExitCode.INTERRUPTED:
        status = RunExit.INTERRUPTED
    summary = catcher.summary
    if summary is not None:
        print("\n".join(format_verdict(summary)))
    return exit_code(summary, status)


def add_accept_parser(sub: argparse._SubParsersAction, bus_arguments: BusArguments) -> None:
    """``accept`` under ``sub``."""
    accept = sub.add_parser(
        "accept", help="goods-in check of a delivered encoder: identity, factory defaults, basic function (seconds)",
        description="A fixed, non-destructive selection of the conformance tests (plugin/acceptance.py says which "
                    "and why) against a device in delivery state: is it the product bought, and does it basically "
                    "work. One verdict per area and overall PASS / FAIL / PASS WITH WARNINGS; exit code 0 pass, "
                    "1 fail, 69 could not test, 70 not restored.")
    command_arguments(accept, "accept", bus_arguments)  # plugin/option_table.py: the rows 'accept' takes
    accept.add_argument("--verbose", action="store_true", help="show pytest's own output too")
    accept.set_defaults(func=_cmd_accept)
