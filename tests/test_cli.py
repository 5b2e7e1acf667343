"""The command line: faults, profile list, and ``sim`` serving a simulator on python-can-remote.

The quick commands run as subprocesses started together by one module fixture; ``sim`` is
started through sim.process.start_simulator, which waits for its READY line.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import can
import pytest

from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.profile.loader import DEFAULT_PROFILE_DIR
from encoder_conformance.sim.fault_catalogue import FAULTS, VARIANTS
from encoder_conformance.sim.process import SimulatorControl, start_simulator

REPO = Path(__file__).resolve().parents[1]
MINIMAL = REPO / "tests" / "data" / "profiles" / "minimal-encoder.yaml"

COMMANDS = {
    "faults": ["faults"],
    "profile-list": ["profile", "list"],
    "no-command": [],
    "stray-argument": ["faults", "--bogus"],
    "sim-unknown-profile": ["sim", "--profile", "does-not-exist", "--listen", "127.0.0.1:0"],
}


@pytest.fixture(scope="module")
def runs() -> dict[str, subprocess.CompletedProcess[str]]:
    """Run every command at once; results keyed like COMMANDS."""
    started = {
        name: (args, subprocess.Popen([sys.executable, "-m", "encoder_conformance", *args], cwd=REPO, text=True,
                                      stdout=subprocess.PIPE, stderr=subprocess.PIPE))
        for name, args in COMMANDS.items()
    }
    results = {}
    for name, (args, process) in started.items():
        try:
            stdout, stderr = process.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            process.kill()
            stdout, stderr = process.communicate()
        results[name] = subprocess.CompletedProcess(args, process.returncode, stdout, stderr)
    return results


def test_faults_lists_every_fault(runs):
    """'faults' prints one line per named fault with its description, sorted, exit 0."""
    result = runs["faults"]
    assert result.returncode == 0, result.stderr
    faults, _, variants = result.stdout.partition("\n\nconformant variants")
    names = [line.split()[0] for line in faults.splitlines()]
    assert names == sorted(FAULTS)
    assert [line.split()[0] for line in variants.splitlines()[1:]] == sorted(VARIANTS)
    assert FAULTS["wrong_vendor_id"] in result.stdout


def test_profile_list_shows_every_profile(runs):
    """'profile list' prints every profile id with its title, marks abstract ones, finds none invalid."""
    result = runs["profile-list"]
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    rows = {line.split()[0]: line for line in result.stdout.splitlines() if line.strip()}
    assert set(rows) == {path.stem for path in DEFAULT_PROFILE_DIR.glob("*.yaml")}
    assert "(abstract)" in rows["wachendorff-wdga-base"]
    assert "(abstract)" not in rows["wachendorff-wdga-mt"]
    assert "Wachendorff WDGA multiturn" in rows["wachendorff-wdga-mt"]
    invalid = [row for row in rows.values() if "INVALID" in row]
    assert not invalid, invalid


def test_missing_command_is_an_argparse_error(runs):
    """No sub-command: usage message, exit 4 (usage error), no traceback."""
    result = runs["no-command"]
    assert result.returncode == 4  # usage error (RunExit.USAGE_ERROR)
    assert "usage:" in result.stderr
    assert "Traceback" not in result.stderr


def test_unknown_argument_is_refused(runs):
    """Extra arguments are only passed on by 'run'; elsewhere they are refused."""
    result = runs["stray-argument"]
    assert result.returncode == 4  # usage error (RunExit.USAGE_ERROR)
    assert "--bogus" in result.stderr
    assert "Traceback" not in result.stderr


def test_sim_serves_the_bus_and_the_control_channel(tmp_path):
    """'sim' prints READY with its endpoints; a remote client sees the boot-up after a power cycle; stops on SIGTERM."""
    log_path = tmp_path / "sim.log"
    sim = start_simulator(str(MINIMAL), nvm_path=tmp_path / "nvm.json", log_path=log_path)
    try:
        assert sim.can_url.startswith("ws://127.0.0.1:")
        assert sim.node_id == 5
        assert sim.process.poll() is None
        control = SimulatorControl(sim.control)
        try:
            assert control.describe()["profile"] == "minimal-encoder"
            bus = can.Bus(**sim.bus_kwargs)
            frames = FrameLog()
            notifier = can.Notifier(bus, [frames], timeout=0.05)
            try:
                mark = frames.mark()
                control.power_cycle()
                boot = frames.wait_for(lambda m: m.arbitration_id == 0x705 and bytes(m.data) == b"\x00", 5.0, mark)
                assert boot is not None, "no boot-up seen through python-can-remote after power_cycle"
            finally:
                notifier.stop()
                bus.shutdown()
        finally:
            control.close()
    finally:
        sim.stop()
    assert sim.process.returncode == 0, log_path.read_text(encoding="utf-8")[-2000:]


def test_sim_with_unknown_profile_exits_without_traceback(runs):
    """'sim --profile does-not-exist' fails with the profile error and exit 4, no traceback."""
    result = runs["sim-unknown-profile"]
    assert result.returncode == 4  # usage error (RunExit.USAGE_ERROR)
    assert "does-not-exist" in result.stderr
    assert "Traceback" not in result.stderr


def test_a_bug_of_the_tool_exits_3_not_1(monkeypatch, capsys):
    """An exception no command expects is the tool's internal error (3), never 'non-conformant' (1)."""
    from encoder_conformance.cli import profile as profile_command
    from encoder_conformance.cli.main import main

    def broken(args, extra):
        raise RuntimeError("boom")

    monkeypatch.setattr(profile_command, "_cmd_profile_effects", broken)
    assert main(["profile", "effects"]) == 3
    err = capsys.readouterr().err
    assert "RuntimeError: boom" in err
    assert "internal error of the tool" in err


def test_a_closed_output_pipe_ends_the_command_quietly():
    """`encoder-conformance profile list | head -1`: the reader is gone before the output comes (the pipe's read end
    is closed before the command starts, so the write fails every time); exit 141 as after SIGPIPE, no traceback."""
    import os

    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        done = subprocess.run([sys.executable, "-m", "encoder_conformance", "profile", "list"], cwd=REPO,
                              stdout=write_end, stderr=subprocess.PIPE, text=True, timeout=120, check=False)
    finally:
        os.close(write_end)
    assert done.returncode == 141, done.stderr
    assert done.stderr == ""
