"""The suite's options, declared once: each is a pytest option (``pytest suites --help``, group "CANopen encoder
conformance"), and many are also options of ``encoder-conformance run`` and ``accept``, with the same help text.

From this table come the pytest options (``add_pytest_options``: the plugin's ``pytest_addoption`` in
plugin/hooks.py calls it), the ``run``/``accept`` arguments and the shared bus arguments of every command
that opens a bus (cli/usage.py reads it), and the pytest arguments a ``run`` or ``accept`` hands over
(``pytest_argv``). A new option is one row here; ``tests/test_option_table.py`` keeps both sides equal to it.

A row's name is the commands' (``--station``); pytest knows it with the plugin's prefix (``--ec-station``, dest
``ec_station``), as hypothesis prefixes its options ``--hypothesis-`` and labgrid ``--lg-``: the entry point
adds them to every pytest session where the package is installed, so none of them may take a name another
plugin or pytest itself has (DESIGN.md "Options"). The pytest spellings before the prefix (``Option.former``)
still work in the suites' own sessions for one release (plugin/former_spellings.py). The command line checks
some values more strictly than pytest does (``kind``): a bit rate may be given as 250k there, a node-ID outside
1..127 is refused while parsing; pytest takes plain numbers and the plugin's ``configure`` checks them.

Light on purpose (the command line imports it at every start): no pytest, no python-can, no pydantic.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from encoder_conformance.paths import DEFAULT_PROFILE

if TYPE_CHECKING:
    from collections.abc import Mapping

    import pytest

Command = Literal["run", "accept"]
#: what a value is: how pytest and the command line convert it (cli/usage.py maps the last two to its checks)
Kind = Literal["text", "int", "float", "bitrate", "node-id"]
Action = Literal["store", "store_true", "append"]

GROUP = "encoder-conformance"
GROUP_TITLE = "CANopen encoder conformance"
PROFILE_ENV = "ENCODER_CONFORMANCE_PROFILE"
#: what every pytest option of the plugin begins with (DESIGN.md "Options" says why this one)
PREFIX = "--ec-"
TRACE_POLICIES = ("failed", "all", "none")
RUN_AND_ACCEPT: frozenset[Command] = frozenset({"run", "accept"})
RUN: frozenset[Command] = frozenset({"run"})
ACCEPT: frozenset[Command] = frozenset({"accept"})


@dataclass(frozen=True)
class Option:
    """One option: its name, its help (the same on both sides), and how the commands take it."""

    name: str  #: the commands' name, e.g. "--station"; pytest's is the prefixed ``pytest_name``, "--ec-station"
    help: str
    commands: frozenset[Command] = frozenset()  #: the encoder-conformance commands that take it too (none: pytest only)
    #: the pytest spelling before the prefix where it was not ``name`` (pytest's own --strict and --trace, and
    #: pytest-profiling's --profile, took the plain names)
    former: str | None = None
    action: Action = "store"
    kind: Kind = "text"
    default: object = None  #: pytest's default (an append option's: an empty list); the commands pass on what is given
    choices: tuple[str, ...] | None = None
    metavar: str | None = None
    command_default: str | None = None  #: the commands' default, where they pass one on though not given
    required_by: frozenset[Command] = frozenset()
    several: bool = False  #: the commands take it several times (one run per value, in parallel); pytest once

    @property
    def pytest_name(self) -> str:
        """The name pytest knows it by: the commands' name with the plugin's prefix."""
        return PREFIX + self.name.removeprefix("--")

    @property
    def former_name(self) -> str:
        """The pytest spelling before the prefix (deprecated, plugin/former_spellings.py)."""
        return self.former or self.name

    @property
    def dest(self) -> str:
        """pytest's attribute name (``config.option.DEST``), prefixed as the name is."""
        return _dest(self.pytest_name)

    @property
    def cli_dest(self) -> str:
        """The attribute of the commands' parsed arguments."""
        return _dest(self.name)


def _dest(name: str) -> str:
    return name.removeprefix("--").replace("-", "_")


#: every option, in the order both sides list them
OPTIONS: tuple[Option, ...] = (
    Option("--profile", former="--device-profile", commands=RUN_AND_ACCEPT, required_by=ACCEPT,
           command_default=DEFAULT_PROFILE, metavar="PROFILE",
           help=f"the device profile: an id (`encoder-conformance profile list`) or a YAML file; for accept the "
                f"profile bought, which it requires. Default {DEFAULT_PROFILE}; plain pytest takes ${PROFILE_ENV} "
                "first"),
    Option("--can-interface", commands=RUN_AND_ACCEPT, metavar="NAME",
           help="python-can interface: pcan, kvaser, socketcan, ixxat, slcan, remote, virtual ... (default: the "
                "station file's, else python-can's configuration: CAN_INTERFACE, ~/can.conf; for a run with none "
                "anywhere: the profile's built-in simulator)"),
    Option("--can-channel", commands=RUN_AND_ACCEPT, metavar="CHANNEL",
           help="the adapter's channel: PCAN_USBBUS1, can0, ws://HOST:PORT/ ... (default: the station file's, else "
                "python-can's configuration)"),
    Option("--can-bitrate", commands=RUN_AND_ACCEPT, kind="bitrate", metavar="BIT/S",
           help="bit rate in bit/s, e.g. 250000 (the encoder-conformance commands also take 250k, 1M; default: the "
                "station file's, else python-can's configuration)"),
    Option("--node-id", commands=RUN_AND_ACCEPT, kind="node-id", metavar="1..127",
           help="the device's node-ID, 1..127 (default: the station file's, else the profile's delivery node-ID)"),
    Option("--station", commands=RUN_AND_ACCEPT, several=True, metavar="FILE",
           help="station file (TOML or YAML): the bench's CAN adapter, node-ID, power switch, operator, motor "
                "plug-in, report and history locations; options given override it. run and accept take it several "
                "times: one device per station, in parallel"),
    Option("--label-serial", commands=RUN_AND_ACCEPT, kind="int", metavar="NUMBER",
           help="the serial number printed on the device's label (decimal): the identity tests check that the "
                "device reports it (1018h sub 4, else 650Bh), and the history finds a device that reports none by "
                "it (default: none; on the built-in simulator the twin's own, profile simulator.serial_number)"),
    Option("--report-dir", commands=RUN_AND_ACCEPT, metavar="DIR",
           help="folder for report.html, junit.xml, run-summary.json and the traces (and allure-results with "
                "--allure) (default reports/<timestamp>-<profile>/, or under the station file's reports); with "
                "several --station: the parent of one folder per station"),
    Option("--history", commands=ACCEPT, metavar="PATH",
           help="the history the run is appended to: an SQLite file, or a postgresql://user@host/db URL that many "
                "stations share (default: the station file's history, else $ENCODER_CONFORMANCE_HISTORY, else "
                "reports/history.sqlite); 'off' records nothing"),
    Option("--allow-destructive", commands=RUN, action="store_true", default=False,
           help="on hardware, allow tests that change what the device remembers (store, restore defaults, "
                "node-ID); the run puts it all back (default: off; always on for the simulator)"),
    Option("--delivery-state", commands=RUN, action="store_true", default=False,
           help="the device is in its delivery state (fresh from the factory, never configured): check its factory "
                "defaults as found, without restoring defaults first (no --allow-destructive needed; default: off)"),
    Option("--power-off-cmd", commands=RUN, metavar="CMD",
           help="shell command that switches the device off (with --power-on-cmd; default: the station file's): "
                "the power-cycle tests run on the bench instead of skipping"),
    Option("--power-on-cmd", commands=RUN, metavar="CMD", help="shell command that switches the device on"),
    Option("--power-manual", commands=RUN, action="store_true", default=False,
           help="ask the operator at the terminal to switch the power off and on (default: off)"),
    Option("--power-off-time", commands=RUN, kind="float", metavar="SECONDS",
           help="seconds the power stays off in a power cycle (default 1.0, 0 on the simulator)"),
    Option("--shaft-drive", commands=ACCEPT, metavar="MODULE:FACTORY[=ARGUMENT]",
           help="bench only: a plug-in that turns the encoder's shaft (a motor): FACTORY(config) returns an object "
                "with turn_by(revolutions) and set_speed(revolutions_per_second); config.argument is the text after "
                "'='. Default: the station file's; without one the tests that need rotation skip on a bench"),
    Option("--sim-fault", commands=RUN_AND_ACCEPT, action="append", metavar="NAME",
           help="built-in simulator only: inject a named fault; repeatable (`encoder-conformance faults` lists the "
                "names)"),
    Option("--sim-profile", commands=ACCEPT, metavar="PROFILE",
           help="built-in simulator only: the profile the twin plays (default: the device profile). A twin of "
                "another device shows how a wrong profile, or a delivery of another product, fails"),
    Option("--sim-inprocess", action="store_true", default=False,
           help="built-in simulator only: run it in the test process on the virtual interface (faster start, less "
                "accurate timing)"),
    Option("--strict", former="--strict-inferred", commands=RUN_AND_ACCEPT, action="store_true", default=False,
           help="fail a device also on rules we only inferred (a manual's silence, an example); by default a device "
                "that breaks only such rules passes with a warning"),
    Option("--trace", former="--bus-trace", commands=RUN_AND_ACCEPT, choices=TRACE_POLICIES, default="failed",
           help="which tests keep their bus trace (traces/<test>.asc and .log, candump format): 'failed' (default: "
                "failed, error and warning tests), 'all', or 'none'"),
    Option("--abort-codes", choices=("exact", "family"), default="exact",
           help="how SDO abort codes are judged: 'exact' (default) the code CiA 301 or the manual names for the "
                "situation; 'family' any code that differs only in its last digit (06090031h for 06090030h), as "
                "the CiA conformance test tool accepts"),
    Option("--budget", kind="float", default=1.0, metavar="SECONDS",
           help="wall-clock time each property test (hypothesis sequences against the device) may spend generating "
                "examples (default 1 s; raise it for long bench runs)"),
    Option("--fuzz-budget", kind="float", metavar="SECONDS",
           help="wall-clock time each SDO fuzz test may spend sending examples; once spent, it stops (default: no "
                "limit, the hypothesis profile's example count decides; set it on a bench)"),
    Option("--allure", action="store_true", default=False,
           help="also write allure-pytest results (allure-results/ in the report folder, with the run's verdict, "
                "device and settings as environment; render with `npx -p allure-commandline allure generate`, Java "
                "needed). Off by default: about 3,400 files and 3 s of a 14 s WDGA run"),
    Option("--shuffle", kind="int", metavar="SEED",
           help="run the suite modules and the tests inside each in a random order drawn from SEED (the same SEED "
                "gives the same order): shows tests that inherit a state"),
    Option("--run-kind", choices=("run", "accept"), default="run",
           help="what kind of run the history records (set by `encoder-conformance accept`)"),
)

#: the bus options every command that opens a bus takes (cli/usage.py bus_arguments), and the node-ID
BUS_OPTIONS = ("--can-interface", "--can-channel", "--can-bitrate")
NODE_ID_OPTION = "--node-id"
_PYTEST_TYPES: dict[Kind, type[int] | type[float] | None] = {
    "text": None, "int": int, "float": float, "bitrate": int, "node-id": int}


def option(name: str) -> Option:
    """The option of this name (the commands' name, e.g. "--station")."""
    return next(entry for entry in OPTIONS if entry.name == name)


def pytest_name(name: str) -> str:
    """The pytest spelling of the option the commands call ``name``: ``pytest_name("--station")`` is "--ec-station"."""
    return option(name).pytest_name


#: pytest's spelling of the bus-trace policy (plugin/options.py trace_policy reads it)
TRACE_OPTION = pytest_name("--trace")


def options_of(command: Command) -> tuple[Option, ...]:
    """The options ``command`` takes, in table order."""
    return tuple(entry for entry in OPTIONS if command in entry.commands)


def pytest_attributes(entry: Option) -> dict[str, object]:
    """What pytest's ``addoption`` is given for ``entry`` beside its name: action, default, help, type, choices."""
    attributes: dict[str, object] = {"action": entry.action, "default": entry.default, "help": entry.help,
                                     "dest": entry.dest}
    if entry.action != "store_true":
        attributes.update(type=_PYTEST_TYPES[entry.kind], metavar=entry.metavar, choices=entry.choices)
    if entry.action == "append":
        attributes["default"] = []  # a fresh list: pytest keeps the default object
    return {key: value for key, value in attributes.items() if value is not None}


def add_pytest_options(parser: pytest.Parser) -> None:
    """Every option of the table, as a pytest option of the suite's group."""
    group = parser.getgroup(GROUP, GROUP_TITLE)
    for entry in OPTIONS:
        group.addoption(entry.pytest_name, **pytest_attributes(entry))


def pytest_argv(command: Command, given: Mapping[str, object]) -> list[str]:
    """The pytest arguments for what ``command`` was given (its parsed arguments, e.g. ``vars(args)``): each of its
    options that was given (or has a command default), under its pytest name."""
    argv: list[str] = []
    for entry in options_of(command):
        value = given.get(entry.cli_dest)
        if isinstance(value, bool):
            argv += [entry.pytest_name] if value else []
        elif isinstance(value, list | tuple):
            for item in value:
                argv += [entry.pytest_name, str(item)]
        elif value is not None:
            argv += [entry.pytest_name, str(value)]
    return argv


def pytest_spellings(words: list[str]) -> list[str]:
    """The arguments a ``run`` passes on to pytest with the suite's pytest-only options in the commands' spelling
    (``--budget 5``, ``--shuffle=3``, as ``run`` took them before the prefix) turned into pytest's
    (``--ec-budget 5``); every other word as given."""
    renamed = {entry.name: entry.pytest_name for entry in OPTIONS}
    spelled = []
    for word in words:
        name, equals, value = word.partition("=")
        spelled.append(renamed[name] + equals + value if name in renamed else word)
    return spelled


#: entry-point plugins a conformance run never uses: anyio's (no async tests), allure-pytest's unless asked for
_UNUSED_PLUGINS = ("anyio",)
_ALLURE_PLUGIN = "allure_pytest"


def unused_plugins(extra: list[str]) -> list[str]:
    """``-p no:...`` for the installed pytest plugins this run does not use: importing allure-pytest (and the attrs
    it brings) cost ~60 ms of every run's start-up, anyio's ~10 ms (measured with ``-X importtime``). allure-pytest
    stays where ``--ec-allure`` (or its former spelling) or its own ``--alluredir`` (among the arguments passed on to
    pytest) asks for results."""
    allure = option("--allure")
    asking = (allure.pytest_name, allure.former_name)
    wants_allure = any(arg in asking or arg.startswith("--alluredir") for arg in extra)
    names = [*_UNUSED_PLUGINS, *(() if wants_allure else (_ALLURE_PLUGIN,))]
    return [arg for name in names for arg in ("-p", f"no:{name}")]


def imported_before_pytest(modules: tuple[str, ...]) -> list[str]:
    """``-W`` filters for pytest's warning that it cannot rewrite the asserts of ``modules``, imported before the
    session on purpose (the command line imports this package first; the self-tests' fork server preloads more):
    noise in every run's summary otherwise. pytest takes a -W message literally: one filter per module."""
    return [arg for name in modules for arg in (
        "-W", f"ignore:Module already imported so cannot be rewritten; {name}:pytest.PytestAssertRewriteWarning")]
