"""The ``run`` command: its arguments (documented with their defaults) and the hand-over to pytest.

Arguments ``run`` does not know go to pytest; several ``--station`` files run in parallel (stations.py).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from encoder_conformance.cli import usage as usage
from encoder_conformance.cli.usage import UsageError, bus_arguments
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.paths import DEFAULT_PROFILE, SUITES_DIR


def pytest_arguments(extra: list[str]) -> list[str]:
    """What goes to pytest: the arguments ``run`` does not know, with the ``--`` that may separate them dropped
    (to pytest a ``--`` would turn every option after it into a file name)."""
    return [arg for arg in extra if arg != "--"]


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

    args.station = args.station[0] if args.station else None
    argv = [str(SUITES_DIR), "--device-profile", args.profile, "-p", "no:cacheprovider"]
    for option in ("can_interface", "can_channel", "can_bitrate", "node_id", "report_dir", "station", "label_serial",
                   "power_off_cmd", "power_on_cmd", "power_off_time"):
        value = getattr(args, option)
        if value is not None:
            argv += [f"--{option.replace('_', '-')}", str(value)]
    for flag in ("allow_destructive", "power_manual", "delivery_state"):
        if getattr(args, flag):
            argv.append(f"--{flag.replace('_', '-')}")
    if args.strict:
        argv.append("--strict-inferred")  # pytest's own --strict is about markers and config
    for fault in args.sim_fault:
        argv += ["--sim-fault", fault]
    if args.trace:
        argv += ["--bus-trace", args.trace]  # pytest's own --trace is its debugger
    status = int(pytest.main(argv + pytest_arguments(extra)))
    # pytest's own 'interrupted' (2) comes only from a Ctrl-C before the run's signal handling was set up
    return RunExit.INTERRUPTED if status == pytest.ExitCode.INTERRUPTED else status


RUN_EPILOG = """\
Arguments 'run' does not know go to pytest, with or without a '--' before them, e.g.
  encoder-conformance run --profile waycon-sx -k heartbeat -x
  encoder-conformance run -- --durations=10
The suite's own pytest options (see 'pytest suites --help', group "CANopen encoder conformance"):
  --abort-codes exact|family   how SDO abort codes are judged (default exact: the code CiA 301 or
                               the manual names; family: any code of the same family, as the CTT)
  --allure                     also write allure-pytest results (allure-results/ in the report folder)
  --budget SECONDS             time each property test spends generating examples (default 1)
  --fuzz-budget SECONDS        time each SDO fuzz test may spend (default: the example count decides)
  --shaft-drive MODULE:FACTORY[=ARG]   bench plug-in that turns the shaft (a motor)
  --sim-inprocess              run the built-in simulator in the test process (faster start)
  -k EXPRESSION                only the tests whose names match (pytest's -k)
  -x                           stop at the first failure (pytest's -x)
  -q / -v                      less / more output; the live progress line shows only on a
                               terminal, without -q/-v, and not where CI is set

Several --station files run their devices in parallel, one process each, with one combined
table at the end (each station's report folder under --report-dir, default reports/).

Exit codes: 0 passed, 1 device non-conformant, 3 internal error, 4 usage error, 5 no tests
selected, 69 could not test, 70 device not restored as found, 130 interrupted (143 SIGTERM).
"""


def add_run_parser(sub: argparse._SubParsersAction[usage.OneLineParser]) -> None:
    # allow_abbrev=False: an abbreviation of ours must not swallow a pytest option (and parallel stations
    # pass the arguments on as given, less --station and --report-dir, which need their full names)
    run = sub.add_parser("run", help="run the conformance suites (extra arguments go to pytest)", epilog=RUN_EPILOG,
                         allow_abbrev=False,
                         formatter_class=argparse.RawDescriptionHelpFormatter,
                         description="Check one device (or one per --station, in parallel) against its profile.\n"
                                     "Without a CAN interface the profile's simulated twin is checked.")
    run.add_argument("--profile", default=DEFAULT_PROFILE,
                     help=f"device profile id (see 'profile list') or YAML file (default {DEFAULT_PROFILE})")
    bus_arguments(run)
    run.add_argument("--station", action="append", default=[], metavar="FILE",
                     help="station file (TOML or YAML): the bench's CAN adapter, node-ID, power switch, operator, "
                          "report and history locations; options given here override it. Give it several times "
                          "to check one device per station in parallel")
    run.add_argument("--label-serial", type=int, metavar="NUMBER",
                        help="the serial number on the device's label: checked against what the device reports "
                             "(1018h sub 4, else 650Bh) and recorded in the history (default: none; on the simulator "
                             "the twin's own)")
    run.add_argument("--report-dir", metavar="DIR",
                     help="folder for the report (default reports/<timestamp>-<profile>/, or under the station's "
                          "reports); with several --station: the parent of one folder per station")
    run.add_argument("--allow-destructive", action="store_true",
                     help="on hardware, allow tests that change what the device remembers (store, restore "
                          "defaults, node-ID); the run puts it all back (default: off; always on for the simulator)")
    run.add_argument("--delivery-state", action="store_true",
                     help="the device is fresh from the factory: check its factory defaults as found (default: off)")
    run.add_argument("--power-off-cmd", metavar="CMD",
                     help="shell command that switches the device off (with --power-on-cmd; default: the station "
                          "file's; none: the power-cycle tests skip on a bench)")
    run.add_argument("--power-on-cmd", metavar="CMD", help="shell command that switches the device on")
    run.add_argument("--power-manual", action="store_true",
                     help="ask the operator at the terminal to switch the power (default: off)")
    run.add_argument("--power-off-time", type=float, metavar="S", help="seconds the power stays off (default 1.0)")
    run.add_argument("--sim-fault", action="append", default=[], metavar="NAME",
                     help="built-in simulator only: inject a named fault; repeatable (names: "
                          "'encoder-conformance faults')")
    run.add_argument("--strict", action="store_true",
                     help="fail a device also on rules we only inferred (pytest option --strict-inferred); by "
                          "default they give warnings")
    run.add_argument("--trace", choices=("failed", "all", "none"),
                     help="which tests keep their bus trace (ASC and candump log): failed (default: failed, error "
                          "and warning tests), all, none (pytest option --bus-trace)")
    run.set_defaults(func=cmd_run)
