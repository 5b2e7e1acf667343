"""Usage errors of the command line: each is one line on stderr naming the option or file and the fix,
exit code 4, no traceback, and comes before any work is done.

In-process through ``cli.main`` (fast); a subprocess only where a real port must be taken.
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from encoder_conformance.cli import main as cli
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.plugin import interrupt
from encoder_conformance.profile.loader import DEFAULT_PROFILE_DIR

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(autouse=True)
def _keep_signal_handlers(monkeypatch: pytest.MonkeyPatch) -> None:
    """cli.main installs its early Ctrl-C handler: not in the test process."""
    monkeypatch.setattr(interrupt, "catch_early", lambda: None)


def usage_error(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    """Run the command in-process; assert a usage error (exit 4, one line, no traceback); return the line."""
    try:
        code = cli.main(list(argv))
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    err = capsys.readouterr().err
    assert code == RunExit.USAGE_ERROR, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


@pytest.fixture
def taken_port() -> Iterator[int]:
    """A port some other program listens on."""
    with socket.socket() as other:
        other.bind(("127.0.0.1", 0))
        other.listen()
        yield other.getsockname()[1]


def run_cli(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "encoder_conformance", *argv], cwd=REPO, text=True,
                          capture_output=True, timeout=60)


def assert_one_line_usage_error(result: subprocess.CompletedProcess[str]) -> str:
    assert result.returncode == RunExit.USAGE_ERROR, result.stderr
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    return lines[0]


def test_sim_on_a_listen_port_in_use(taken_port):
    """'sim --listen' on a port another program holds names the option, the port and the fix."""
    line = assert_one_line_usage_error(run_cli("sim", "--profile", "waycon-sx", "--listen",
                                               f"127.0.0.1:{taken_port}"))
    assert f"--listen 127.0.0.1:{taken_port}" in line
    assert "in use" in line
    assert "another port" in line


def test_sim_on_a_control_port_in_use(taken_port):
    """The same for the control channel's port."""
    line = assert_one_line_usage_error(run_cli("sim", "--profile", "waycon-sx", "--listen", "127.0.0.1:0",
                                               "--control", f"127.0.0.1:{taken_port}"))
    assert f"--control 127.0.0.1:{taken_port}" in line
    assert "in use" in line


def test_sim_with_an_unknown_fault(capsys):
    """'sim --fault x' says where the names are, not the 150 names themselves."""
    line = usage_error(capsys, "sim", "--profile", "waycon-sx", "--fault", "x")
    assert "--fault x: unknown fault" in line
    assert "encoder-conformance faults" in line


def test_a_fault_name_with_a_typo_gets_the_nearest_names(capsys):
    line = usage_error(capsys, "sim", "--profile", "waycon-sx", "--fault", "heartbeat_slow_20")
    assert "did you mean heartbeat_slow_20pct" in line


def test_sim_listen_without_a_port(capsys):
    line = usage_error(capsys, "sim", "--profile", "waycon-sx", "--listen", "localhost")
    assert "--listen" in line
    assert "HOST:PORT" in line


def test_sim_copies_beyond_the_last_node_id(capsys):
    line = usage_error(capsys, "sim", "--profile", "waycon-sx", "--copies", "3", "--node-id", "126")
    assert "--copies 3" in line
    assert "start lower" in line


def test_from_eds_of_a_missing_file(capsys, tmp_path):
    line = usage_error(capsys, "profile", "from-eds", str(tmp_path / "nope.eds"))
    assert "nope.eds: no such file" in line
    assert "EDS" in line


def test_sim_nvm_naming_a_folder(capsys, tmp_path):
    line = usage_error(capsys, "sim", "--profile", "waycon-sx", "--nvm", str(tmp_path))
    assert f"--nvm {tmp_path}: is a folder" in line


def test_to_eds_into_a_missing_folder(capsys, tmp_path):
    line = usage_error(capsys, "profile", "to-eds", "waycon-sx", "-o", str(tmp_path / "no" / "x.eds"))
    assert "does not exist" in line


def test_run_report_dir_naming_a_file(capsys, tmp_path):
    existing = tmp_path / "a-file"
    existing.write_text("x", encoding="utf-8")
    line = usage_error(capsys, "run", "--report-dir", str(existing))
    assert f"--report-dir {existing}: is a file" in line
    assert "give a folder" in line


def test_fault_matrix_with_an_unknown_fault_refuses_at_once(capsys):
    """Before the fault-free baseline run (12 s of work), not after it."""
    started = time.monotonic()
    line = usage_error(capsys, "fault-matrix", "--profile", "waycon-sx", "--fault", "x")
    assert "--fault x: unknown fault" in line
    assert time.monotonic() - started < 3


def test_profile_validate_a_folder_validates_every_profile_in_it(capsys):
    """A folder is every *.yaml in it, one 'ok' line each."""
    assert cli.main(["profile", "validate", str(DEFAULT_PROFILE_DIR)]) == 0
    out = capsys.readouterr().out
    assert len(out.strip().splitlines()) == len(list(DEFAULT_PROFILE_DIR.glob("*.yaml")))


def test_profile_validate_a_folder_without_profiles(capsys, tmp_path):
    line = usage_error(capsys, "profile", "validate", str(tmp_path))
    assert str(tmp_path) in line
    assert "no *.yaml" in line


@pytest.mark.parametrize("argv", [
    ["run", "--profile", "wdga-mt"],
    ["sim", "--profile", "wdga-mt"],
    ["fault-matrix", "--profile", "wdga-mt"],
    ["repeat", "--profile", "wdga-mt"],
    ["lss", "scan", "--can-interface", "virtual", "--can-channel", "usage-test", "--profile", "wdga-mt"],
    ["profile", "to-eds", "wdga-mt"],
    ["profile", "validate", "wdga-mt"],
], ids=lambda argv: argv[0] if argv[0] != "profile" else "-".join(argv[:2]))
def test_an_unknown_profile_id(capsys, argv):
    """Every command that takes a profile: one line with the nearest ids and where the list is."""
    line = usage_error(capsys, *argv)
    assert "wdga-mt: no profile with this id" in line
    assert "did you mean wachendorff-wdga-mt" in line
    assert "profile list" in line


@pytest.mark.parametrize("argv", [
    ["run", "--node-id", "0"],
    ["run", "--node-id", "200"],
    ["sim", "--profile", "waycon-sx", "--node-id", "0"],
    ["restore", "--from", "x.json", "--node-id", "128"],
    ["profile", "to-eds", "waycon-sx", "--node-id", "abc"],
], ids=["run-0", "run-200", "sim-0", "restore-128", "to-eds-abc"])
def test_a_node_id_out_of_range(capsys, argv):
    line = usage_error(capsys, *argv)
    assert "--node-id" in line
    assert "1..127" in line


def test_a_bit_rate_that_is_no_number(capsys):
    line = usage_error(capsys, "run", "--can-bitrate", "abc")
    assert "--can-bitrate" in line
    assert "250000" in line


def test_restore_from_a_missing_snapshot(capsys, tmp_path):
    line = usage_error(capsys, "restore", "--from", str(tmp_path / "missing.json"), "--can-interface", "virtual",
                       "--can-channel", "usage-test")
    assert "missing.json" in line
    assert "cannot read the snapshot" in line


def test_run_with_a_missing_station_file(capsys, tmp_path):
    line = usage_error(capsys, "run", "--station", str(tmp_path / "bench.toml"))
    assert "--station" in line
    assert "bench.toml" in line


def test_run_with_an_unknown_simulator_fault(capsys):
    line = usage_error(capsys, "run", "--profile", "waycon-sx", "--sim-fault", "x")
    assert "--sim-fault x: unknown fault" in line


def test_sim_control_address_without_a_port(capsys):
    line = usage_error(capsys, "sim-control", "--control", "localhost", "power-off")
    assert "--control" in line
    assert "HOST:PORT" in line


@pytest.mark.parametrize("argv", [["repeat", "--runs", "0"], ["fault-matrix", "--workers", "0"]],
                         ids=["repeat-runs", "fault-matrix-workers"])
def test_counts_below_one(capsys, argv):
    line = usage_error(capsys, *argv)
    assert argv[1] in line
    assert "positive" in line


def test_an_unknown_command(capsys):
    line = usage_error(capsys, "bogus")
    assert "invalid choice: 'bogus'" in line
    assert "--help" in line


def test_run_help_documents_every_option_and_the_pytest_side(capsys):
    """Every option of 'run' with its default, and what goes to pytest."""
    with pytest.raises(SystemExit):
        cli.main(["run", "--help"])
    text = capsys.readouterr().out
    parser = cli.build_parser()
    run = next(action for action in parser._subparsers._group_actions[0].choices.items()  # type: ignore[union-attr]
               if action[0] == "run")[1]
    for action in run._actions:
        assert action.help, f"{action.option_strings} has no help"
        for option in action.option_strings:
            assert option in text
    for pytest_side in ("--abort-codes", "--trace", "--allure", "--budget", "--fuzz-budget", "-k", "-x"):
        assert f"  {pytest_side} " in text
    assert "go to pytest" in text
    assert "default" in text


@pytest.mark.parametrize(("passed_on", "allure_loaded"), [
    ([], False), (["--allure"], True), (["--alluredir=out"], True), (["--alluredir", "out"], True),
    (["-k", "x"], False),
])
def test_a_run_loads_allure_pytest_only_where_results_are_asked_for(passed_on, allure_loaded):
    from encoder_conformance.plugin.option_table import unused_plugins

    blocked = unused_plugins(passed_on)
    assert ("no:allure_pytest" not in blocked) == allure_loaded
    assert "no:anyio" in blocked
    assert all(a == "-p" for a in blocked[::2])


def test_a_module_imported_before_pytest_on_purpose_gives_no_warning_line():
    """The command line imports this package before pytest: pytest's cannot-rewrite warning about it is filtered,
    one literal -W per module (pytest escapes a -W message)."""
    from encoder_conformance.plugin.option_table import imported_before_pytest

    message = "ignore:Module already imported so cannot be rewritten; {}:pytest.PytestAssertRewriteWarning"
    assert imported_before_pytest(("encoder_conformance", "hypothesis")) == [
        "-W", message.format("encoder_conformance"), "-W", message.format("hypothesis")]
