"""The suite's pytest options as they were spelled before the prefix (``--station`` for ``--ec-station``): accepted
for one release, hidden from ``--help``, each use a ``PytestDeprecationWarning`` naming the new spelling.

A plugin of the suites' own conftest.py, not of the package's entry point: a pytest session of another project
where the package is installed never gets these names (they are the unprefixed ones the prefix took away), only
a session of the suites, where a script written for the old names runs. Remove this module, and its line in
conftest.py, in the release after the prefix came (README "Migrating to the prefixed options").
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

import pytest

from encoder_conformance.plugin import option_table
from encoder_conformance.plugin.option_table import Option

#: where the parse notes which former spellings it met: their new spellings by former spelling
USED = "ec_former_spellings"


class FormerSpelling(argparse.Action):
    """A former spelling: stores into the option's own dest what the option would, and notes its use."""

    def __init__(self, option_strings: Sequence[str], dest: str, option: Option, **kwargs: Any) -> None:
        self.option = option
        if option.action == "store_true":
            kwargs["nargs"] = 0
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: str | None = None) -> None:
        if self.option.action == "store_true":
            values = True
        elif self.option.action == "append":
            values = [*(getattr(namespace, self.dest, None) or []), values]
        setattr(namespace, self.dest, values)
        used = dict(getattr(namespace, USED, None) or {})
        used[option_string or self.option.former_name] = self.option.pytest_name
        setattr(namespace, USED, used)


def pytest_addoption(parser: pytest.Parser) -> None:
    """Every row's former spelling, in the suite's group but not shown in its help."""
    group = parser.getgroup(option_table.GROUP, option_table.GROUP_TITLE)
    for entry in option_table.OPTIONS:
        attributes = {**option_table.pytest_attributes(entry), "action": FormerSpelling, "option": entry,
                      "default": argparse.SUPPRESS, "help": argparse.SUPPRESS}
        group.addoption(entry.former_name, **attributes)


def messages(used: dict[str, str]) -> list[str]:
    """One line per former spelling given."""
    return [f"{former} is deprecated: spell it {new} (the old spelling goes in the next release)"
            for former, new in sorted(used.items())]


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config: pytest.Config) -> None:
    for message in messages(getattr(config.option, USED, None) or {}):
        config.issue_config_time_warning(pytest.PytestDeprecationWarning(message), stacklevel=2)
