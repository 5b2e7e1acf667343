"""Parallel stations: one device per station file, each checked by a process of its own, one combined table.

``encoder-conformance run --station a.toml --station b.toml [--profile P] [...]`` starts
``encoder-conformance run --station a.toml --report-dir PARENT/a [...]`` and the same for b, with every other
argument passed on, and waits for all. Each run has its own bus (the station's adapter and channel, or its
own built-in simulator), report folder and custody of its device; the runs share nothing, so a process
each is simpler and safer than pytest-xdist (whose workers share one session, one report and one device).
The sub-command is a parameter: ``accept`` runs stations the same way.

At the end: one row per station (profile, serial number, overall verdict, failing areas, report folder) read
from each run's run-summary.json, and the worst exit code of the runs. Ctrl-C (or SIGTERM) is passed on to
every run, which gives its device back first; the runs get ``STOP_BOUND_S`` to end, then are killed (with
the restore command to finish the job).
"""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any, TypeAlias

from encoder_conformance.config.station import load_station
from encoder_conformance.deadline import Deadline
from encoder_conformance.errors import UsageError
from encoder_conformance.exit_codes import DESCRIPTIONS, RunExit, interrupted_by
from encoder_conformance.paths import default_reports_dir
from encoder_conformance.run_summary import RunSummary

STOP_BOUND_S = 120.0  # a restore after Ctrl-C takes seconds; a run that needs longer is stuck
CONSOLE_LOG = "console.log"
CLEAR = "\r\x1b[K"  # back to the start of the line, erase it
#: what signal.signal takes and gives back: a function, SIG_DFL/SIG_IGN, or None (a handler not set from Python)
SignalHandler: TypeAlias = Callable[[int, FrameType | None], Any] | int | signal.Handlers | None

#: exit codes from least to most serious: the combined run ends with the most serious one
SEVERITY: tuple[int, ...] = (RunExit.PASSED, RunExit.NO_TESTS, RunExit.INCOMPLETE, RunExit.NON_CONFORMANT,
                             RunExit.COULD_NOT_TEST,
                             RunExit.USAGE_ERROR, RunExit.INTERNAL_ERROR, RunExit.INTERRUPTED,
                             interrupted_by(signal.SIGTERM), RunExit.NOT_RESTORED)


@dataclass
class StationRun:
    """One station's run: its process and where it writes."""

    station_file: str
    name: str
    report_dir: Path
    process: subprocess.Popen[bytes] | None = None
    started: float = 0.0
    exit_code: int | None = None
    ended: float = 0.0

    @property
    def console(self) -> Path:
        return self.report_dir / CONSOLE_LOG


@dataclass
class Row:
    """One line of the combined table."""

    station: str
    profile: str
    serial: str
    verdict: str
    failing: str
    exit_code: int
    report_dir: str
    cells: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        self.cells = (self.station, self.profile, self.serial, self.verdict, self.failing, str(self.exit_code),
                      self.report_dir)


def worst_exit(codes: Sequence[int]) -> int:
    """The most serious of the runs' exit codes (an unknown code counts as an internal error)."""
    def rank(code: int) -> int:
        return SEVERITY.index(code) if code in SEVERITY else SEVERITY.index(RunExit.INTERNAL_ERROR)

    return max(codes, key=rank) if codes else RunExit.NO_TESTS


def strip_options(arguments: Sequence[str], options: set[str]) -> list[str]:
    """``arguments`` without the given options and their values (``--opt V`` or ``--opt=V``); what follows a
    ``--`` is pytest's and is kept as it is."""
    kept: list[str] = []
    skip_value = False
    for position, arg in enumerate(arguments):
        if skip_value:
            skip_value = False
        elif arg == "--":
            return kept + list(arguments[position:])
        elif arg in options:
            skip_value = True
        elif not any(arg.startswith(f"{option}=") for option in options):
            kept.append(arg)
    return kept


def plan_stations(station_files: Sequence[str], parent: Path) -> list[StationRun]:
    """One run per station file; its report folder is named after the station (the file's name if two
    stations share a name). UsageError if two stations name the same CAN channel."""
    stations = [load_station(Path(path)) for path in station_files]
    buses: dict[tuple[str, str], str] = {}
    for path, station in zip(station_files, stations, strict=True):
        if station.can is not None and station.can.channel is not None:
            bus = (station.can.interface, station.can.channel)
            if bus in buses:
                raise UsageError(f"--station {path}: uses the CAN channel {bus[1]} ({bus[0]}) of --station "
                                 f"{buses[bus]}; parallel stations need a bus each")
            buses[bus] = path
    names = [station.station for station in stations]
    runs = []
    for path, name in zip(station_files, names, strict=True):
        folder_name = name if names.count(name) == 1 else f"{name}-{Path(path).stem}"
        runs.append(StationRun(path, name, parent / _safe(folder_name)))
    return runs


def child_command(command: str, run: StationRun, arguments: Sequence[str]) -> list[str]:
    """``encoder-conformance COMMAND --station FILE --report-dir FOLDER`` and the other arguments as given."""
    rest = strip_options(arguments, {"--station", "--report-dir"})
    return [sys.executable, "-m", "encoder_conformance", command, "--station", run.station_file,
            "--report-dir", str(run.report_dir), *rest]


def run_stations(command: str, station_files: Sequence[str], argv: Sequence[str], report_parent: str | None) -> int:
    """Check one device per station in parallel; print the combined table; return the worst exit code.
    ``argv`` is the command line as given (from the sub-command on)."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    parent = Path(report_parent) if report_parent else default_reports_dir() / f"{stamp}-stations"
    arguments = list(argv[argv.index(command) + 1:]) if command in argv else list(argv)
    runs = plan_stations(station_files, parent)
    ended: queue.Queue[StationRun] = queue.Queue()
    with _ForwardSignals(runs) as forward:
        for run in runs:
            _start(command, run, arguments, ended)
        _wait_all(runs, ended, forward)
    rows = [row_of(run) for run in runs]
    print(format_table(rows), flush=True)
    return worst_exit([row.exit_code for row in rows])


def row_of(run: StationRun) -> Row:
    """The table row of a finished run, from its run-summary.json (or what is known without one)."""
    code = RunExit.INTERNAL_ERROR if run.exit_code is None else run.exit_code
    try:
        summary = RunSummary.read(run.report_dir)
    except (OSError, ValueError, KeyError, TypeError):
        why = DESCRIPTIONS.get(code, f"exit {code}")
        return Row(run.name, "-", "-", f"NO SUMMARY ({why}; see {CONSOLE_LOG})", "-", code, str(run.report_dir))
    verdict: str = summary.overall
    if code in (RunExit.INTERRUPTED, interrupted_by(signal.SIGTERM)):
        verdict = f"INTERRUPTED ({verdict} so far)"  # not every test ran: no verdict about the device
    return Row(run.name, summary.profile_id, summary.serial or "-", verdict,
               ", ".join(summary.failing_areas()) or "-", code, str(run.report_dir))


def format_table(rows: Sequence[Row]) -> str:
    """A plain-text table with a header, columns as wide as their widest cell."""
    header = ("station", "profile", "serial", "verdict", "failing areas", "exit", "report folder")
    widths = [max(len(cells[i]) for cells in (header, *(row.cells for row in rows))) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(width) for cell, width in zip(cells, widths, strict=True)).rstrip()
             for cells in (header, *(row.cells for row in rows))]
    lines.insert(1, "  ".join("-" * width for width in widths))
    return "\n".join(lines)


def _start(command: str, run: StationRun, arguments: Sequence[str], ended: queue.Queue[StationRun]) -> None:
    run.report_dir.mkdir(parents=True, exist_ok=True)
    with open(run.console, "wb") as console:
        # a session of its own: the terminal's Ctrl-C reaches this process only, which passes it on once
        run.process = subprocess.Popen(child_command(command, run, arguments), stdout=console,
                                       stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)
    run.started = time.monotonic()
    print(f"station {run.name}: running ({command}, pid {run.process.pid}); output in {run.console}", flush=True)

    def wait() -> None:
        assert run.process is not None
        code = run.process.wait()
        run.exit_code = interrupted_by(-code) if code < 0 else code  # killed by a signal: the shell's number
        run.ended = time.monotonic()
        ended.put(run)

    threading.Thread(target=wait, name=f"station-{run.name}", daemon=True).start()


def status_line(runs: Sequence[StationRun], now: float) -> str:
    """'running: bench-a 0:42, bench-b 0:42' (the stations still running and for how long)."""
    from encoder_conformance.plugin.progress import clock_text

    running = [f"{run.name} {clock_text(now - run.started)}" for run in runs if run.exit_code is None]
    return "running: " + ", ".join(running)


def _wait_all(runs: list[StationRun], ended: queue.Queue[StationRun], forward: _ForwardSignals) -> None:
    """Report each run as it ends; after a forwarded Ctrl-C, kill what is still running at the bound. On a
    terminal (not in CI) a line below says which stations still run, and for how long."""
    live = sys.stdout.isatty() and not os.environ.get("CI")
    remaining = len(runs)
    while remaining:
        if live:
            print(f"{CLEAR}{status_line(runs, time.monotonic())}", end="", flush=True)
        # wakes once a second: a signal handler cannot interrupt the wait, and its deadline must be seen
        timeout = 1.0 if forward.deadline is None else min(forward.deadline.remaining(), 1.0)
        try:
            run = ended.get(timeout=timeout)
        except queue.Empty:
            if forward.deadline is None or not forward.deadline.expired():
                continue
            print(CLEAR if live else "", end="", flush=True)
            for run in runs:
                if run.process is not None and run.process.poll() is None:
                    print(f"station {run.name}: still running {STOP_BOUND_S:.0f} s after the stop; killed. Its "
                          f"device may not be as found: encoder-conformance restore --from "
                          f"{run.report_dir / 'device-snapshot.json'}", file=sys.stderr, flush=True)
                    run.process.kill()
            forward.deadline = None
            continue
        remaining -= 1
        print(CLEAR if live else "", end="")
        code = run.exit_code
        assert code is not None  # set before the run is queued as ended (_start)
        verdict = DESCRIPTIONS.get(code, f"exit {code}")
        print(f"station {run.name}: ended after {run.ended - run.started:.0f} s: {verdict} (exit {code})",
              flush=True)


class _ForwardSignals:
    """While the runs go on: SIGINT/SIGTERM go to every run still running (each then gives its device back)."""

    def __init__(self, runs: list[StationRun]) -> None:
        self._runs = runs
        self._previous: dict[int, SignalHandler] = {}
        self.deadline: Deadline | None = None

    def __enter__(self) -> _ForwardSignals:
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._previous[sig] = signal.signal(sig, self._forward)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)

    def _forward(self, signum: int, frame: FrameType | None) -> None:
        running = [(run.name, run.process) for run in self._runs
                   if run.process is not None and run.process.poll() is None]
        for _, process in running:
            process.send_signal(signum)
        if self.deadline is None:
            self.deadline = Deadline(STOP_BOUND_S)
        names = ", ".join(name for name, _ in running) or "none"
        print(f"\n{signal.Signals(signum).name} passed on to the stations still running ({names}); each gives its "
              f"device back first", file=sys.stderr, flush=True)


def _safe(name: str) -> str:
    """A station name as a folder name."""
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name) or "station"
