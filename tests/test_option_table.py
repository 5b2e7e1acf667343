"""One table of options (encoder_conformance/plugin/option_table.py) feeds the pytest options and the ``run`` and
``accept`` parsers: both sides hold exactly its rows, show the same help, differ in name only where the table says
why, and what ``run``/``accept`` hand to pytest parses back to the values given (issue 27). In-process, no run."""

from __future__ import annotations

import argparse

import pytest
from _pytest.config.argparsing import Parser

from encoder_conformance.cli import main as cli
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.history.db import ENV_VAR, OFF
from encoder_conformance.paths import DEFAULT_PROFILE
from encoder_conformance.plugin import acceptance, history_hook, hooks, shuffle, verdicts
from encoder_conformance.plugin import option_table as table
from encoder_conformance.plugin.options import TRACE_OPTION

COMMANDS: tuple[table.Command, ...] = ("run", "accept")
#: what a command takes beyond the table (it does not reach pytest as an option)
OWN_OPTIONS = {"run": {"-h", "--help"}, "accept": {"-h", "--help", "--verbose"}}
#: the names that differ between pytest and the commands; the table says why (Option.renamed)
RENAMED = {"--device-profile": "--profile", "--strict-inferred": "--strict", "--bus-trace": "--trace"}


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
    assert [option.names() for option in group.options] == [[row.name] for row in table.OPTIONS]
    assert len({row.name for row in table.OPTIONS}) == len(table.OPTIONS)


def test_pytest_keeps_its_defaults_choices_and_types():
    """Parsing nothing gives the defaults the plugin always had; values are converted as before."""
    given = vars(pytest_parser().parse_known_args([]))
    assert {key: value for key, value in given.items() if value not in (None, False)} == {
        "file_or_dir": [], "sim_fault": [], "bus_trace": "failed", "abort_codes": "exact", "budget": 1.0,
        "run_kind": "run"}
    options = pytest_options()
    assert options["--bus-trace"].choices == ("failed", "all", "none")
    assert options["--abort-codes"].choices == ("exact", "family")
    assert options["--run-kind"].choices == ("run", "accept")
    assert {name for name, action in options.items() if action.type is int} == {
        "--can-bitrate", "--node-id", "--label-serial", "--shuffle"}
    assert {name for name, action in options.items() if action.type is float} == {
        "--power-off-time", "--budget", "--fuzz-budget"}


def test_the_modules_read_options_the_table_declares():
    """The names the plugin's modules read with getoption are rows of the table."""
    names = {row.name for row in table.OPTIONS}
    for used in (TRACE_OPTION, verdicts.STRICT_OPTION, history_hook.OPTION, shuffle.OPTION, acceptance.KIND_OPTION):
        assert used in names
    history = table.option(history_hook.OPTION).help
    assert f"${ENV_VAR}" in history
    assert f"'{OFF}'" in history
    assert DEFAULT_PROFILE in table.option("--device-profile").help


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_option_is_in_the_table(command):
    """The command's options are its rows of the table (and -h, and accept's --verbose), none missing."""
    given = set(command_options(command))
    assert given - OWN_OPTIONS[command] == {row.cli_name for row in table.options_of(command)}


@pytest.mark.parametrize("command", COMMANDS)
def test_help_is_the_same_on_both_sides(command):
    """A shared option shows pytest's help text, word for word, also its choices and value name."""
    on_pytest = pytest_options()
    for row in table.options_of(command):
        ours, theirs = command_options(command)[row.cli_name], on_pytest[row.name]
        assert ours.help == theirs.help == row.help_text, row.name
        assert ours.choices == theirs.choices, row.name
        assert ours.metavar == theirs.metavar, row.name


def test_every_bus_command_shows_the_same_bus_help():
    """restore and lss open a bus too: the same options with the same help (cli/usage.py bus_arguments)."""
    on_pytest = pytest_options()
    for name in (*table.BUS_OPTIONS, table.NODE_ID_OPTION):
        assert command_options("restore")[name].help == on_pytest[name].help


def test_names_differ_only_where_the_table_says_why():
    """Three names differ, each with its reason, and both sides' help names both."""
    differing = {row.name: row.cli_name for row in table.OPTIONS if row.cli_name != row.name}
    assert differing == RENAMED
    for name, cli_name in RENAMED.items():
        row = table.option(name)
        assert row.renamed
        assert f"pytest: {name}" in row.help_text
        assert f"run and accept: {cli_name}" in row.help_text
    assert all(row.command_name is None and not row.renamed for row in table.OPTIONS if row.name not in RENAMED)


def test_run_help_lists_the_pytest_only_options_with_their_help(capsys):
    """'run --help' names every row 'run' does not take, with the table's help (wrapped), after its own."""
    with pytest.raises(SystemExit):
        cli.main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for row in table.OPTIONS:
        if "run" not in row.commands:
            assert f" {row.name} " in text
            assert " ".join(row.help_text.split()) in text


def _sample(row: table.Option) -> tuple[list[str], object]:
    """Command-line words for ``row`` and the value pytest must see for them."""
    if row.action == "store_true":
        return [row.cli_name], True
    if row.choices:
        return [row.cli_name, row.choices[-1]], row.choices[-1]
    word, value = {"int": ("7", 7), "float": ("2.5", 2.5), "bitrate": ("250k", 250_000), "node-id": ("5", 5),
                   "text": (f"{row.dest}-value", f"{row.dest}-value")}[row.kind]
    if row.action == "append":
        return [row.cli_name, word, row.cli_name, f"{word}-2"], [value, f"{word}-2"]
    return [row.cli_name, word], value


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


def test_run_renamed_options_are_handed_over_under_pytest_names():
    """run --profile X --trace --strict ... gives pytest --device-profile X --bus-trace --strict-inferred ..."""
    args, _ = cli.build_parser().parse_known_args(
        ["run", "--profile", "waycon-sx", "--trace", "all", "--strict", "--can-bitrate", "1M", "--station", "a.toml"])
    handed = table.pytest_argv("run", vars(args))
    assert handed == ["--device-profile", "waycon-sx", "--can-bitrate", "1000000", "--station", "a.toml",
                      "--strict-inferred", "--bus-trace", "all"]


def test_what_is_not_given_is_not_handed_over():
    """A plain run passes only its profile (run's default, so that $ENCODER_CONFORMANCE_PROFILE does not apply);
    pytest's defaults decide the rest."""
    args, _ = cli.build_parser().parse_known_args(["run"])
    assert table.pytest_argv("run", vars(args)) == ["--device-profile", DEFAULT_PROFILE]
    args, _ = cli.build_parser().parse_known_args(["accept", "--profile", "waycon-sx"])
    assert table.pytest_argv("accept", vars(args)) == ["--device-profile", "waycon-sx"]


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
