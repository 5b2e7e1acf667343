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

from encoder_conformance.exit_codes import RunExit
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
    argv = [*pytest_args(), "--device-profile", args.profile, KIND_OPTION, KIND, "-p", "no:cacheprovider",
            "--assert=plain"]
    for option in ("can_interface", "can_channel", "can_bitrate", "node_id", "report_dir", "station", "label_serial",
                   "shaft_drive", "sim_profile", "history"):
        value = getattr(args, option)
        if value is not None:
            argv += [f"--{option.replace('_', '-')}", str(value)]
    if args.strict:
        argv.append("--strict-inferred")
    for fault in args.sim_fault:
        argv += ["--sim-fault", fault]
    if args.trace:
        argv += ["--bus-trace", args.trace]  # pytest's own --trace is its debugger
    if not args.verbose:
        argv += ["-p", "no:terminal"]
    return argv


def format_verdict(summary: RunSummary) -> list[str]:
    """One line per area, the first failure under a failed area, the overall verdict and the report folder."""
    identity = summary.identity
    lines = [f"accept {summary.profile_id}: serial {summary.serial or '-'}, revision {summary.revision or '-'}"
             + (f", device name {identity['device name (1008h)']}" if identity.get("device name (1008h)") else "")]
    for area in summary.areas():
        counts = ", ".join(f"{n} {what}" for n, what in ((area.passed, "passed"), (area.failed, "failed"),
                                                         (area.warnings, "warnings"), (area.skipped, "skipped")) if n)
        lines.append(f"  {area.area:18s} {area.verdict:18s} ({counts})")
        if area.verdict == "FAIL":
            failed = next(r for r in summary.results if r.area == area.area and r.outcome in ("failed", "error"))
            first = (failed.message.strip().splitlines() or [""])[0].removeprefix("AssertionError: ")
            lines.append(f"      {failed.nodeid.split('/')[-1]}: {first[:MESSAGE_WIDTH]}")
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
    args.station = args.station[0] if args.station else None
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
    accept.add_argument("--profile", required=True, help="the device profile bought (id or file)")
    bus_arguments(accept)
    accept.add_argument("--station", action="append", default=[], metavar="FILE",
                        help="station file (TOML or YAML): CAN adapter, node-id, operator, motor plug-in, where "
                             "reports and the history go. Give it several times to accept one device per station in "
                             "parallel")
    accept.add_argument("--history", metavar="PATH",
                        help="the history database the acceptance is appended to (default: the station's history, "
                             "else $ENCODER_CONFORMANCE_HISTORY, else reports/history.sqlite); 'off' records nothing")
    accept.add_argument("--label-serial", type=int, metavar="NUMBER",
                        help="the serial number on the device's label: checked against what the device reports "
                             "(1018h sub 4, else 650Bh) and recorded in the history (default: none; on the simulator "
                             "the twin's own)")
    accept.add_argument("--report-dir", help="where to write the report (default <station reports or reports>/"
                                             "<timestamp>-<profile>)")
    accept.add_argument("--shaft-drive", metavar="MODULE:FACTORY[=ARGUMENT]",
                        help="bench only: motor plug-in that turns the shaft (see run --help; or the station's)")
    accept.add_argument("--sim-fault", action="append", default=[], help="simulator fault (see 'faults')")
    accept.add_argument("--sim-profile", help="simulator only: the twin plays this profile instead (a delivery of "
                                              "another product)")
    accept.add_argument("--strict", action="store_true",
                        help="fail also on rules we only inferred (default: they give PASS WITH WARNINGS)")
    accept.add_argument("--trace", choices=("failed", "all", "none"),
                        help="which tests keep their bus trace (ASC and candump log): failed (default), all, none")
    accept.add_argument("--verbose", action="store_true", help="show pytest's own output too")
    accept.set_defaults(func=_cmd_accept)
