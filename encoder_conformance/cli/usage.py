"""Usage errors of the command line: one line on stderr naming the option or file and the fix, exit code 4;
the argument types, the bus options the commands share and the option table's rows as arguments.

Every command checks what it was given before it starts any work (a fault name, a profile id, a port),
so that a typo costs no time and shows no traceback. The checks raise ``UsageError``; ``cli.main`` prints
``encoder-conformance COMMAND: MESSAGE`` and returns RunExit.USAGE_ERROR. argparse's own errors come out
the same way (``OneLineParser``) instead of argparse's usage block and exit code 2.

Light on purpose (the command line imports it at every start): no python-can, no pytest.
"""

from __future__ import annotations

import argparse
import difflib
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, NoReturn

from encoder_conformance.cia.cia305 import MAX_NODE_ID
from encoder_conformance.errors import ProfileError, UsageError
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.plugin import option_table


class OneLineParser(argparse.ArgumentParser):
    """argparse with the suite's usage-error exit code (4) and a one-line message pointing to ``--help``."""

    def error(self, message: str) -> NoReturn:
        self.exit(RunExit.USAGE_ERROR, f"{self.prog}: error: {message} (usage: {self.prog} --help)\n")


def node_id_arg(text: str) -> int:
    """argparse type: a CANopen node-ID, 1..127 (CiA 301 §7.5.2.2)."""
    value = int(text) if text.strip().isdigit() else 0
    if not 1 <= value <= MAX_NODE_ID:
        raise argparse.ArgumentTypeError(f"{text!r} is not a node-ID: give 1..{MAX_NODE_ID}")
    return value


def positive_int(text: str) -> int:
    """argparse type: a whole number >= 1."""
    value = int(text) if text.strip().isdigit() else 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive whole number")
    return value


def bitrate(text: str) -> int:
    """argparse type: a bit rate in bit/s ('250000', or '250k', '1M')."""
    scaled = text.strip().lower().replace("k", "000").replace("m", "000000")
    if not scaled.isdigit() or int(scaled) < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a bit rate: give bit/s, e.g. 250000 or 250k")
    return int(scaled)


def host_port(text: str) -> str:
    """argparse type: 'HOST:PORT' (or ':PORT'), port 0..65535 (0: any free port)."""
    _host, colon, port = text.rpartition(":")
    if not colon or not port.isdigit() or int(port) > 65535:
        raise argparse.ArgumentTypeError(f"{text!r} is not HOST:PORT: give e.g. 127.0.0.1:54701 (port 0 picks a "
                                         "free one)")
    return text


#: how the command line converts each kind of value of the option table (pytest takes plain numbers)
_TYPES: dict[option_table.Kind, Callable[[str], object] | None] = {
    "text": None, "int": int, "float": float, "bitrate": bitrate, "node-id": node_id_arg}


def table_argument(parser: argparse.ArgumentParser, option: option_table.Option,
                   command: option_table.Command | None = None) -> None:
    """One option of the table (plugin/option_table.py) as an argument of ``command``'s parser: its command-line
    name, the help pytest shows too; given nowhere, it is not passed on (None, or an empty list)."""
    kwargs: dict[str, Any] = {"help": option.help}
    if option.action == "store_true":
        kwargs["action"] = "store_true"
    else:
        kwargs.update(type=_TYPES[option.kind], metavar=option.metavar, choices=option.choices)
    if option.action == "append" or option.several:
        kwargs.update(action="append", default=[])
    if command is not None and command in option.required_by:
        kwargs["required"] = True
    elif option.command_default is not None:
        kwargs["default"] = option.command_default
    parser.add_argument(option.name, **{key: value for key, value in kwargs.items() if value is not None})


def command_arguments(parser: argparse.ArgumentParser, command: option_table.Command,
                      bus: Callable[..., None] | None = None) -> None:
    """Every option of the table that ``command`` takes, in table order; the bus options through ``bus`` (default
    bus_arguments) where the first of them comes."""
    skipped = {*option_table.BUS_OPTIONS, option_table.NODE_ID_OPTION}
    for option in option_table.options_of(command):
        if option.name == option_table.BUS_OPTIONS[0]:
            (bus or bus_arguments)(parser)
        if option.name not in skipped:
            table_argument(parser, option, command)


def bus_arguments(parser: argparse.ArgumentParser, node_id: bool = True) -> None:
    """--can-interface/-channel/-bitrate (and --node-id): the same meaning in every command that opens a bus, and
    the same help as the pytest options (plugin/option_table.py)."""
    for name in (*option_table.BUS_OPTIONS, option_table.NODE_ID_OPTION) if node_id else option_table.BUS_OPTIONS:
        table_argument(parser, option_table.option(name))


def check_profile(option: str, name: str) -> None:
    """A profile id that exists or a profile file; else a UsageError with the nearest ids."""
    from encoder_conformance.profile.loader import (  # yaml: only when a command names a profile
        DEFAULT_PROFILE_DIR,
        find_profile,
    )

    try:
        find_profile(name)
    except ProfileError:
        if Path(name).suffix or Path(name).exists() or "/" in name or "\\" in name:
            raise UsageError(f"{option} {name}: no such profile file; give a profile id or the path of a .yaml "
                             "file") from None
        ids = sorted(path.stem for path in DEFAULT_PROFILE_DIR.glob("*.yaml"))  # the names: parsing 33 files is slow
        raise UsageError(f"{option} {name}: no profile with this id{_did_you_mean(name, ids)}; "
                         "`encoder-conformance profile list` lists them") from None


def check_faults(option: str, names: Iterable[str]) -> None:
    """Every name is a simulator fault or conformant variant; else a UsageError naming the first unknown one."""
    from encoder_conformance.sim.fault_catalogue import SIMULATOR_DEVIATIONS

    for name in names:
        if name not in SIMULATOR_DEVIATIONS:
            raise UsageError(f"{option} {name}: unknown fault{_did_you_mean(name, SIMULATOR_DEVIATIONS)}; "
                             "`encoder-conformance faults` lists the names")


def check_report_dir(option: str, path: str | None) -> None:
    """A report folder may exist (it is written into) but must not be a file."""
    if path is not None and Path(path).exists() and not Path(path).is_dir():
        raise UsageError(f"{option} {path}: is a file, not a folder; give a folder (it is created if missing)")


def check_output_file(option: str, path: Path | None) -> None:
    """A file the command will write: not a folder, and its folder exists."""
    if path is None:
        return
    if path.is_dir():
        raise UsageError(f"{option} {path}: is a folder; give a file name (in that folder, e.g. {path / 'NAME'})")
    if not path.parent.is_dir():
        raise UsageError(f"{option} {path}: the folder {path.parent} does not exist; create it or give another path")


def profile_files(names: Iterable[str]) -> list[str]:
    """The profile files to validate: names as given, a folder as every *.yaml in it."""
    files: list[str] = []
    for name in names:
        folder = Path(name)
        if folder.is_dir():
            found = sorted(str(p) for p in folder.glob("*.yaml"))
            if not found:
                raise UsageError(f"{name}: a folder with no *.yaml profile in it; give profile files or a folder "
                                 "that holds some")
            files += found
        else:
            files.append(name)  # a missing one is reported in its turn (profile validate shows every problem)
    return files


def profile_error_text(exc: ProfileError) -> str:
    """One line where the profile has one problem; one line per problem otherwise."""
    if len(exc.problems) == 1:
        try:
            check_profile("profile", exc.path)  # an unknown id: the short message with the nearest ids
        except UsageError as unknown:
            return str(unknown)
        return f"{exc.path}: {exc.problems[0]}"
    return str(exc)


def report(prog: str, message: str) -> int:
    """Print a usage error and return its exit code."""
    print(f"{prog}: {message}", file=sys.stderr)
    return RunExit.USAGE_ERROR


def _did_you_mean(name: str, known: Iterable[str]) -> str:
    names = list(known)
    close = [known_name for known_name in names if name in known_name][:3]
    close = close or difflib.get_close_matches(name, names, n=3)
    return f" (did you mean {' or '.join(close)}?)" if close else ""


def bench_bus(args: argparse.Namespace, why: str) -> Any:  # -> config.bus.BusConfig (imported lazily)
    """The real bus a bench command names (--can-interface/--can-channel/--can-bitrate or python-can's
    configuration); UsageError naming what to give, ``why`` saying what the built-in simulator would not do."""
    from encoder_conformance.config.bus import resolve_bench_bus
    from encoder_conformance.errors import BusSetupError

    try:
        return resolve_bench_bus(args.can_interface, args.can_channel, args.can_bitrate, why)
    except BusSetupError as exc:
        raise UsageError(str(exc)) from None
