"""One table of options (encoder_conformance/plugin/option_table.py) feeds the pytest options and the ``run`` and
``accept`` parsers: both sides hold exactly its rows, show the same help, pytest's names are the commands' with the
plugin's prefix (issue 41), and what ``run``/``accept`` hand to pytest parses back to the values given (issue 27).
In-process, no run."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest
from _pytest.config.argparsing import Parser

from encoder_conformance.cli import main as cli
from encoder_conformance.cli import run as run_cli
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.history.db import ENV_VAR, OFF
from encoder_conformance.paths import DEFAULT_PROFILE
from encoder_conformance.plugin import acceptance, history_hook, hooks, shuffle, verdicts
from encoder_conformance.plugin import option_table as table
from encoder_conformance.plugin.options import TRACE_OPTION

REPO = Path(__file__).resolve().parents[1]
COMMANDS: tuple[table.Command, ...] = ("run", "accept")
#: what a command takes beyond the table (it does not reach pytest as an option)
OWN_OPTIONS = {"run": {"-h", "--help"}, "accept": {"-h", "--help", "--verbose"}}
#: the pytest spellings before the prefix that were not the commands' names (Option.former)
FORMER = {"--profile": "--device-profile", "--strict": "--strict-inferred", "--trace": "--bus-trace"}


def pytest_parser() -> Parser:
    """A parser with only what the plugin's pytest_addoption declares (pytest's own options are not in it)."""
    parser = Parser(_ispytest=True)  # the constructor pytest itself uses
    hooks.pytest_addoption(parser)
    return parser


def pytest_options() -> dict[str, argparse.Action]:
    """The plugin's pytest options by name, as argparse holds them (type, default, help as pytest shows them)."""
    actions = pytest_parser().optparser._actions  # the argparse parser pytest's groups add to
    return {name: action for action in actions for name in action.option_strings if name.startswith("--")
            and name != "--help"}


def command_parser(command: str) -> argparse.ArgumentParser:
    subparsers = next(action for action in cli.build_parser()._actions
                      if isinstance(action, argparse._SubParsersAction))
    return subparsers.choices[command]


def command_options(command: str) -> dict[str, argparse.Action]:
    return {name: action for action in command_parser(command)._actions for name in action.option_strings}


def test_the_plugin_declares_exactly_the_table():
    """Every pytest option of the plugin is a row of the table, in one group, in table order, and nothing else."""
    parser = pytest_parser()
    assert [group.name for group in parser._groups] == ["_anonymous", table.GROUP]
    assert parser._anonymous.options == []
    group = parser.getgroup(table.GROUP)
    assert group._arggroup.title == table.GROUP_TITLE
    assert [option.names() for option in group.options] == [[row.pytest_name] for row in table.OPTIONS]
    assert len({row.name for row in table.OPTIONS}) == len(table.OPTIONS)
    assert all(row.pytest_name.startswith(table.PREFIX) and row.dest.startswith("ec_") for row in table.OPTIONS)


def test_pytest_keeps_its_defaults_choices_and_types():
    """Parsing nothing gives the defaults the plugin always had; values are converted as before."""
    given = vars(pytest_parser().parse_known_args([]))
    assert {key: value for key, value in given.items() if value not in (None, False)} == {
        "file_or_dir": [], "ec_sim_fault": [], "ec_trace": "failed", "ec_abort_codes": "exact", "ec_budget": 1.0,
        "ec_run_kind": "run"}
    options = pytest_options()
    assert options["--ec-trace"].choices == ("failed", "all", "none")
    assert options["--ec-abort-codes"].choices == ("exact", "family")
    assert options["--ec-run-kind"].choices == ("run", "accept")
    assert {name for name, action in options.items() if action.type is int} == {
        "--ec-can-bitrate", "--ec-node-id", "--ec-label-serial", "--ec-shuffle"}
    assert {name for name, action in options.items() if action.type is float} == {
        "--ec-power-off-time", "--ec-budget", "--ec-fuzz-budget"}


def test_the_modules_read_options_the_table_declares():
    """The names the plugin's modules read with getoption are rows of the table."""
    names = {row.pytest_name for row in table.OPTIONS}
    for used in (TRACE_OPTION, verdicts.STRICT_OPTION, history_hook.OPTION, shuffle.OPTION, acceptance.KIND_OPTION):
        assert used in names
    history = table.option("--history").help
    assert f"${ENV_VAR}" in history
    assert f"'{OFF}'" in history
    assert DEFAULT_PROFILE in table.option("--profile").help


def test_every_getoption_names_a_row():
    """Every ``getoption("--...")`` in the plugin, fixtures and suites names a row's pytest spelling (or pytest's or
    another plugin's own option): a former spelling would be unknown outside the suites' own sessions."""
    pattern = re.compile(r"""getoption\((?:f?)["'](--[a-z{}-]+)["']""")
    names = {row.pytest_name for row in table.OPTIONS} | {"--ec-can-{key}", "--hypothesis-seed"}
    used = {match for folder in ("encoder_conformance", "fixtures", "suites") for path in (REPO / folder).rglob("*.py")
            for match in pattern.findall(path.read_text(encoding="utf-8"))}
    assert used
    assert used - names == set()


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_option_is_in_the_table(command):
    """The command's options are its rows of the table (and -h, and accept's --verbose), none missing."""
    given = set(command_options(command))
    assert given - OWN_OPTIONS[command] == {row.name for row in table.options_of(command)}


@pytest.mark.parametrize("command", COMMANDS)
def test_help_is_the_same_on_both_sides(command):
    """A shared option shows pytest's help text, word for word, also its choices and value name."""
    on_pytest = pytest_options()
    for row in table.options_of(command):
        ours, theirs = command_options(command)[row.name], on_pytest[row.pytest_name]
        assert ours.help == theirs.help == row.help, row.name
        assert ours.choices == theirs.choices, row.name
        assert ours.metavar == theirs.metavar, row.name


def test_every_bus_command_shows_the_same_bus_help():
    """restore and lss open a bus too: the same options with the same help (cli/usage.py bus_arguments)."""
    on_pytest = pytest_options()
    for name in (*table.BUS_OPTIONS, table.NODE_ID_OPTION):
        assert command_options("restore")[name].help == on_pytest[table.pytest_name(name)].help


def test_pytest_names_are_the_commands_names_with_the_prefix():
    """One rule maps the names: pytest's is the commands' with the prefix; the former spelling is the commands'
    name but for the three that pytest itself or another plugin had taken."""
    for row in table.OPTIONS:
        assert row.pytest_name == "--ec-" + row.name.removeprefix("--")
        assert row.former_name == FORMER.get(row.name, row.name)
        assert table.pytest_name(row.name) == row.pytest_name


def test_run_passes_the_pytest_only_options_on_under_pytests_names():
    """``run --budget 5`` (a pytest-only row, not one of run's own options) reaches pytest as ``--ec-budget 5``;
    the other arguments as given."""
    words = ["-k", "identity", "--budget", "5", "--shuffle=3", "--history", "off", "--durations=10", "--", "-x"]
    assert run_cli.pytest_arguments(words) == ["-k", "identity", "--ec-budget", "5", "--ec-shuffle=3",
                                               "--ec-history", "off", "--durations=10", "-x"]


def test_run_help_lists_the_pytest_only_options_with_their_help(capsys):
    """'run --help' names every row 'run' does not take, with the table's help (wrapped), after its own."""
    with pytest.raises(SystemExit):
        cli.main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for row in table.OPTIONS:
        if "run" not in row.commands:
            assert f" {row.name} " in text
            assert " ".join(row.help.split()) in text


def _sample(row: table.Option) -> tuple[list[str], object]:
    """Command-line words for ``row`` and the value pytest must see for them."""
    if row.action == "store_true":
        return [row.name], True
    if row.choices:
        return [row.name, row.choices[-1]], row.choices[-1]
    word, value = {"int": ("7", 7), "float": ("2.5", 2.5), "bitrate": ("250k", 250_000), "node-id": ("5", 5),
                   "text": (f"{row.dest}-value", f"{row.dest}-value")}[row.kind]
    if row.action == "append":
        return [row.name, word, row.name, f"{word}-2"], [value, f"{word}-2"]
    return [row.name, word], value


@pytest.mark.parametrize("command", COMMANDS)
def test_every_option_given_to_a_command_reaches_pytest(command):
    """Each option of the command, given, is handed over under its pytest name and parses back to its value."""
    words, expected = [command], {}
    for row in table.options_of(command):
        sample, value = _sample(row)
        words += sample
        expected[row.dest] = value
    args, extra = cli.build_parser().parse_known_args(words)
    assert extra == []
    handed = table.pytest_argv(command, vars(args))
    parsed = vars(pytest_parser().parse_known_args(handed))
    assert {dest: parsed[dest] for dest in expected} == expected
    assert parsed["file_or_dir"] == []  # nothing left over as a file name


def test_run_options_are_handed_over_under_pytest_names():
    """run --profile X --trace --strict ... gives pytest --ec-profile X --ec-trace --ec-strict ..."""
    args, _ = cli.build_parser().parse_known_args(
        ["run", "--profile", "waycon-sx", "--trace", "all", "--strict", "--can-bitrate", "1M", "--station", "a.toml"])
    handed = table.pytest_argv("run", vars(args))
    assert handed == ["--ec-profile", "waycon-sx", "--ec-can-bitrate", "1000000", "--ec-station", "a.toml",
                      "--ec-strict", "--ec-trace", "all"]


def test_what_is_not_given_is_not_handed_over():
    """A plain run passes only its profile (run's default, so that $ENCODER_CONFORMANCE_PROFILE does not apply);
    pytest's defaults decide the rest."""
    args, _ = cli.build_parser().parse_known_args(["run"])
    assert table.pytest_argv("run", vars(args)) == ["--ec-profile", DEFAULT_PROFILE]
    args, _ = cli.build_parser().parse_known_args(["accept", "--profile", "waycon-sx"])
    assert table.pytest_argv("accept", vars(args)) == ["--ec-profile", "waycon-sx"]


@pytest.mark.parametrize(("argv", "words"), [
    (["accept"], "the following arguments are required: --profile"),
    (["run", "--trace", "some"], "argument --trace: invalid choice: 'some'"),
    (["accept", "--profile", "waycon-sx", "--can-bitrate", "fast"], "'fast' is not a bit rate"),
    (["run", "--node-id", "0"], "'0' is not a node-ID: give 1..127"),
], ids=["accept-without-profile", "run-trace", "accept-bitrate", "run-node-id"])
def test_a_bad_value_is_one_line_and_exit_4(capsys, argv, words):
    with pytest.raises(SystemExit) as ended:
        cli.main(argv)
    err = capsys.readouterr().err
    assert ended.value.code == RunExit.USAGE_ERROR
    assert len(err.strip().splitlines()) == 1, err
    assert words in err
