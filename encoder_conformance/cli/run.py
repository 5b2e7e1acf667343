"""The ``run`` command: its arguments (documented with their defaults) and the hand-over to pytest.

Its options are rows of the option table (plugin/option_table.py), which also declares them to pytest and turns
them into pytest's arguments. Arguments ``run`` does not know go to pytest; several ``--station`` files run in
parallel (stations.py).
"""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path

from encoder_conformance.cli import usage as usage
from encoder_conformance.cli.usage import UsageError
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.paths import SUITES_DIR
from encoder_conformance.plugin import option_table


def pytest_arguments(extra: list[str]) -> list[str]:
    """What goes to pytest: the arguments ``run`` does not know, with the ``--`` that may separate them dropped
    (to pytest a ``--`` would turn every option after it into a file name), and the suite's own options spelled as
    pytest knows them (``--budget 5`` is ``--ec-budget 5``: ``run`` keeps the names it always took)."""
    return option_table.pytest_spellings([arg for arg in extra if arg != "--"])


def check_run(args: argparse.Namespace) -> None:
    """What a run can be told is wrong before pytest starts (UsageError): the profile, the report folder, the
    station files, the faults. The plugin checks the same for plain ``pytest suites``."""
    from encoder_conformance.config.station import StationError, load_station

    usage.check_profile("--profile", args.profile)
    usage.check_report_dir("--report-dir", args.report_dir)
    usage.check_faults("--sim-fault", args.sim_fault)
    for station in args.station:
        try:
            load_station(Path(station))
        except StationError as exc:
            raise UsageError(str(exc)) from None


def cmd_run(args: argparse.Namespace, extra: list[str]) -> int:
    check_run(args)
    if len(args.station) > 1:
        from encoder_conformance.runs.stations import run_stations

        return run_stations(args.command, args.station, args.argv, args.report_dir)
    import pytest

    passed_on = pytest_arguments(extra)
    argv = [str(SUITES_DIR), "-p", "no:cacheprovider", *option_table.unused_plugins(passed_on),
            *option_table.imported_before_pytest(("encoder_conformance",)),  # the command line imported it
            *option_table.pytest_argv("run", vars(args))]
    status = int(pytest.main(argv + passed_on))
    # pytest's own 'interrupted' (2) comes only from a Ctrl-C before the run's signal handling was set up
    return RunExit.INTERRUPTED if status == pytest.ExitCode.INTERRUPTED else status


HELP_COLUMN = 30  # where the help of a pytest option starts in the epilog (argparse's own column is 24)
EPILOG_WIDTH = 100


def _pytest_option_lines(option: option_table.Option) -> list[str]:
    """One pytest option of the table for the epilog: its name and value, then its help (the same text)."""
    if option.action == "store_true":
        value = ""
    elif option.choices:
        value = " " + "|".join(option.choices)
    else:
        value = f" {option.metavar or option.dest.upper()}"
    head = f"  {option.name}{value}"
    text = textwrap.wrap(option.help, EPILOG_WIDTH - HELP_COLUMN)
    if len(head) < HELP_COLUMN - 1:
        return [head.ljust(HELP_COLUMN) + text[0], *(" " * HELP_COLUMN + line for line in text[1:])]
    return [head, *(" " * HELP_COLUMN + line for line in text)]


def run_epilog() -> str:
    """What 'run --help' says after its own options: the suite's pytest options 'run' passes on as given (every
    row of the option table that 'run' does not take), pytest's own most used ones, and the exit codes."""
    suite_options = [line for option in option_table.OPTIONS if "run" not in option.commands
                     for line in _pytest_option_lines(option)]
    return "\n".join([
        "Arguments 'run' does not know go to pytest, with or without a '--' before them, e.g.",
        "  encoder-conformance run --profile waycon-sx -k heartbeat -x",
        "  encoder-conformance run -- --durations=10",
        "The suite's own pytest options that 'run' passes on, under these names (plain pytest spells them",
        f"with {option_table.PREFIX}, e.g. {option_table.pytest_name('--budget')}: 'pytest suites --help', group "
        f'"{option_table.GROUP_TITLE}"):',
        *suite_options,
        "and pytest's own, e.g.:",
        "  -k EXPRESSION               only the tests whose names match (pytest's -k)",
        "  -x                          stop at the first failure (pytest's -x)",
        "  -q / -v                     less / more output; the live progress line shows only on a",
        "                              terminal, without -q/-v, and not where CI is set",
        "",
        "Several --station files run their devices in parallel, one process each, with one combined",
        "table at the end (each station's report folder under --report-dir, default reports/).",
        "",
        "Exit codes: 0 passed, 1 device non-conformant, 3 internal error, 4 usage error, 5 no tests",
        "selected, 6 incomplete (nothing failed, but checks in scope were not testable), 69 could not",
        "test, 70 device not restored as found, 130 interrupted (143 SIGTERM).",
        "",
    ])


def add_run_parser(sub: argparse._SubParsersAction[usage.OneLineParser]) -> None:
    # allow_abbrev=False: an abbreviation of ours must not swallow a pytest option (and parallel stations
    # pass the arguments on as given, less --station and --report-dir, which need their full names)
    run = sub.add_parser("run", help="run the conformance suites (extra arguments go to pytest)", epilog=run_epilog(),
                         allow_abbrev=False,
                         formatter_class=argparse.RawDescriptionHelpFormatter,
                         description="Check one device (or one per --station, in parallel) against its profile.\n"
                                     "Without a CAN interface the profile's simulated twin is checked.")
    usage.command_arguments(run, "run")  # plugin/option_table.py: the rows 'run' takes, the help pytest shows
    run.set_defaults(func=cmd_run)
