"""The plugin in a pytest session of another project (issue 41): the package's pytest11 entry point adds its
options to every session where it is installed, so each carries the prefix (``--ec-``) and nothing else happens
there; the former spellings work only in the suites' own sessions, hidden from the help, with a deprecation
warning naming the new spelling."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest
from _pytest.config.argparsing import Parser

from encoder_conformance.plugin import former_spellings, hooks
from encoder_conformance.plugin import option_table as table

REPO = Path(__file__).resolve().parents[1]
PLUGIN = "encoder_conformance.plugin.hooks"  # the entry point's name
#: another project's tests: one plain test, and one that reports what the session holds once it has run
OTHER_PROJECT_TEST = '''
import os, sys


def test_plain():
    assert 1 + 1 == 2


def test_what_the_session_holds(request):
    """The modules of the package loaded, and the child processes of this one (a launched twin would be one)."""
    children = [pid for pid in os.listdir("/proc") if pid.isdigit() and _parent(pid) == os.getpid()]
    loaded = sorted(name for name in sys.modules if name.startswith("encoder_conformance"))
    with open(os.environ["HOLDS_FILE"], "w") as out:
        out.write(repr({"children": children, "loaded": loaded}))


def _parent(pid):
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return int(stat.read().rpartition(")")[2].split()[1])
    except OSError:
        return None
'''


def _other_project(tmp_path: Path) -> Path:
    project = tmp_path / "other-project"
    project.mkdir()
    (project / "test_other.py").write_text(OTHER_PROJECT_TEST, encoding="utf-8")
    return project


def _pytest(project: Path, *args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    environ = {k: v for k, v in os.environ.items() if not k.startswith(("CAN_", "PYTEST_"))}
    # no bytecode cache either way: what the project folder gains is then only what a plugin writes into it
    # (the CI machine leaves PYTHONDONTWRITEBYTECODE unset, and pytest's assertion rewriting writes __pycache__)
    environ["PYTHONDONTWRITEBYTECODE"] = "1"
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", *args], cwd=project,
                          env={**environ, **(env or {})}, capture_output=True, text=True, timeout=120)


def _long_options(help_text: str) -> set[str]:
    """Every long option the help lists (where argparse starts an option's line, not in the wrapped help text)."""
    return {match for line in help_text.splitlines() for match in re.findall(r"^ {2}(?:-\w[ ,]+)?(--[\w-]+)", line)}


def test_another_projects_help_shows_only_prefixed_options(tmp_path):
    """``pytest --help`` in a folder with no conftest.py: what the plugin adds (the help with it, less the help
    without it) is the table's rows, each prefixed; no former spelling appears."""
    project = _other_project(tmp_path)
    with_plugin, without = _pytest(project, "--help"), _pytest(project, "--help", "-p", f"no:{PLUGIN}")
    assert with_plugin.returncode == without.returncode == 0, with_plugin.stderr + without.stderr
    added = _long_options(with_plugin.stdout) - _long_options(without.stdout)
    assert added == {row.pytest_name for row in table.OPTIONS}
    assert all(name.startswith(table.PREFIX) for name in added)
    formers = {row.former_name for row in table.OPTIONS}
    assert formers & _long_options(with_plugin.stdout) == set()


def test_the_plugin_is_inert_in_another_project(tmp_path):
    """Another project's run is the same with the plugin as without it (but for pytest's plugin list and the
    time): no header line, no summary, no report folder, the project's own JUnit and HTML untouched, no fixture
    of ours, no twin process, none of the plugin's heavy modules imported."""
    project = _other_project(tmp_path)
    outputs, junits = {}, {}
    for name, extra in (("with", ()), ("without", ("-p", f"no:{PLUGIN}"))):
        junit, html = tmp_path / f"{name}.xml", tmp_path / f"{name}.html"
        done = _pytest(project, "-v", f"--junitxml={junit}", f"--html={html}", *extra,
                       env={"HOLDS_FILE": str(tmp_path / f"{name}-holds.txt")})
        assert done.returncode == 0, done.stdout + done.stderr
        outputs[name] = _comparable(done.stdout.replace(f"{name}.", "NAME."))
        junits[name] = _comparable(junit.read_text(encoding="utf-8"))
        assert f">{html.name}</title>" in html.read_text(encoding="utf-8")  # pytest-html's own title
    assert outputs["with"] == outputs["without"]
    assert junits["with"] == junits["without"]
    assert sorted(path.name for path in project.iterdir()) == ["test_other.py"]  # no reports/, no history
    holds = eval((tmp_path / "with-holds.txt").read_text(encoding="utf-8"))
    assert holds["children"] == []
    heavy = [name for name in holds["loaded"] if name.split(".")[1:2] in (["sim"], ["dut"], ["models"], ["profile"])]
    assert heavy == [], "imported by the plugin in a session that never asked for it"
    fixtures = _pytest(project, "--fixtures", "-v")
    assert "encoder_conformance" not in fixtures.stdout


def _comparable(text: str) -> list[str]:
    """Output or XML without what differs from run to run (times, the plugin lists, timestamps, host)."""
    text = re.sub(r'(time|timestamp|hostname)="[^"]*"', "", text)
    text = re.sub(r"\d+\.\d+s", "TIME", text)
    return [line for line in text.splitlines() if not line.startswith(("plugins:", "metadata:"))]


# -- the former spellings ------------------------------------------------------------------------------------

def _parser(with_former: bool) -> Parser:
    parser = Parser(_ispytest=True)
    hooks.pytest_addoption(parser)
    if with_former:
        former_spellings.pytest_addoption(parser)
    return parser


def test_former_spellings_set_what_the_new_ones_set():
    """``--station a --bus-trace all --strict-inferred --sim-fault x --sim-fault y`` parses to the values of the
    prefixed spellings, and the parse notes each former spelling it met with its new one."""
    former = vars(_parser(True).parse_known_args(
        ["--station", "a.toml", "--bus-trace", "all", "--strict-inferred", "--sim-fault", "x", "--sim-fault", "y",
         "--budget", "2.5"]))
    new = vars(_parser(True).parse_known_args(
        ["--ec-station", "a.toml", "--ec-trace", "all", "--ec-strict", "--ec-sim-fault", "x", "--ec-sim-fault", "y",
         "--ec-budget", "2.5"]))
    assert former.pop(former_spellings.USED) == {
        "--station": "--ec-station", "--bus-trace": "--ec-trace", "--strict-inferred": "--ec-strict",
        "--sim-fault": "--ec-sim-fault", "--budget": "--ec-budget"}
    assert former == new
    assert former_spellings.USED not in new


def test_every_row_has_a_hidden_former_spelling():
    """Each row's former spelling is accepted in the suites' sessions, and none is shown in their help."""
    parser = _parser(True)
    for row in table.OPTIONS:
        assert parser._opt2dest[row.former_name] == row.dest
    shown = parser.optparser.format_help()
    assert {row.former_name for row in table.OPTIONS} & _long_options(shown) == set()
    assert {row.pytest_name for row in table.OPTIONS} <= _long_options(shown)


def test_a_former_spelling_is_a_deprecation_warning_naming_the_new_one():
    """One PytestDeprecationWarning per former spelling used, naming the new spelling; none without."""
    issued: list[Warning] = []
    config = SimpleNamespace(option=SimpleNamespace(**{former_spellings.USED: {"--budget": "--ec-budget"}}),
                             issue_config_time_warning=lambda warning, stacklevel: issued.append(warning))
    former_spellings.pytest_configure(config)  # type: ignore[arg-type]
    assert [type(w) for w in issued] == [pytest.PytestDeprecationWarning]
    assert str(issued[0]) == "--budget is deprecated: spell it --ec-budget (the old spelling goes in the next release)"
    issued.clear()
    former_spellings.pytest_configure(SimpleNamespace(option=SimpleNamespace(), issue_config_time_warning=None))  # type: ignore[arg-type]
    assert issued == []


def test_the_suites_session_takes_a_former_spelling_with_the_warning(tmp_path):
    """A script of the old names still runs the suites (collecting, here), and is told the new spelling."""
    done = _pytest(REPO, str(REPO / "suites" / "test_identity.py"), "--co", "-q", "--ec-sim-inprocess",
                   "--device-profile", "waycon-sx", "--history", "off", "--ec-report-dir", str(tmp_path))
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert "PytestDeprecationWarning: --device-profile is deprecated: spell it --ec-profile" in done.stdout
    assert "PytestDeprecationWarning: --history is deprecated: spell it --ec-history" in done.stdout
    assert "test_identity.py::" in done.stdout
