"""``encoder-conformance firmware-ci``: the loop a firmware team's CI runs, with the built-in twin in the role of
the firmware simulator (a process on a SocketCAN channel; here the user-space bus, as in a container).

A conformant simulator passes (0) with its artifacts in the report folder and its process restarted by the power
switch; a faulty one fails (1); one that never answers, or exits by itself, is infrastructure (69), not a verdict
on the firmware. Power off lets a simulator behind a shell (or in the README's restart loop) store at shutdown.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest

from encoder_conformance.cli import firmware_ci as fwci
from encoder_conformance.vcan import BuildError, library

PYTHON = [sys.executable, "-m", "encoder_conformance"]
REPO = Path(__file__).resolve().parents[1]
HELPER = [sys.executable, "-m", "encoder_conformance.cli.firmware_ci"]

#: a firmware simulator's stand-in: says it is up, and on SIGTERM stores after a while (as CANopenLinux writes its
#: auto-stored data at shutdown), then ends; with "--reset-once" it ends by itself at its first start (as
#: CANopenLinux does on NMT reset node)
STAND_IN = """
import signal, sys, time
from pathlib import Path
folder = Path(sys.argv[1])
stopping = []
signal.signal(signal.SIGTERM, lambda *_: stopping.append(1))
with open(folder / "starts", "a") as starts:
    starts.write("start\\n")
if "--reset-once" in sys.argv and (folder / "starts").read_text().count("start") == 1:
    time.sleep(0.2)
    sys.exit(0)
(folder / "up").write_text("up")
while not stopping:
    time.sleep(0.01)
time.sleep(0.5)
(folder / "stored").write_text("node-ID 5")
"""

#: CANopenLinux's behaviour without the restart loop: the twin (the arguments), ended with its process at the first
#: NMT reset node addressed to it (or to all)
ENDS_AT_RESET = """
import subprocess, sys
import can
node = int(sys.argv[1])
twin = subprocess.Popen(sys.argv[2:])
with can.Bus(interface="socketcan", channel="vcan0") as bus:
    bus.set_filters([{"can_id": 0, "can_mask": 0x7FF}])
    while twin.poll() is None:
        frame = bus.recv(0.5)
        if frame is not None and frame.data[0] == 0x81 and frame.data[1] in (0, node):
            break
twin.terminate()
twin.wait()
"""

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="SocketCAN (and the user-space bus) is Linux only")


@pytest.fixture(scope="module", autouse=True)
def preload_library() -> Path:
    try:
        return library()
    except BuildError as error:
        pytest.skip(str(error))


def twin(nvm: Path, *faults: str) -> str:
    """The twin as a firmware simulator would be started: on vcan0, its memory in a file across restarts."""
    command = [*PYTHON, "sim", "--profile", "waycon-sx", "--can-interface", "socketcan", "--can-channel", "vcan0",
               "--nvm", str(nvm)]
    for fault in faults:
        command += ["--fault", fault]
    return " ".join(command)


def firmware_ci(folder: Path, simulator: str, *extra: str, tmp: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "ENCODER_CONFORMANCE_VCAN_DIR")}
    if tmp is not None:
        env["TMPDIR"] = str(tmp)  # where firmware-ci makes its state folder
    return subprocess.run([*PYTHON, "firmware-ci", "--simulator", simulator, "--profile", "waycon-sx",
                           "--history", "off", *extra], cwd=folder, env=env, capture_output=True, text=True,
                          timeout=300)


def test_a_conformant_simulator_passes_with_its_artifacts(tmp_path):
    done = firmware_ci(tmp_path, twin(tmp_path / "nvm.json"))
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    report = tmp_path / "conformance-report"
    for artifact in ("junit.xml", "report.html", "run-summary.json", "firmware-simulator.log"):
        assert (report / artifact).is_file(), artifact
    summary = json.loads((report / "run-summary.json").read_text(encoding="utf-8"))
    outcomes = Counter(result["outcome"] for result in summary["results"])
    assert set(outcomes) <= {"passed", "skipped"}, outcomes
    assert outcomes["passed"] > 100, outcomes
    assert summary["device_restored"] is True
    log = (report / "firmware-simulator.log").read_text(encoding="utf-8")
    assert log.count("power on") >= 2  # the power switch restarted the simulator's process
    assert "the user-space SocketCAN bus" in done.stderr


@pytest.fixture
def short_tmp() -> Iterator[Path]:
    """A TMPDIR for firmware-ci with a short path (the hub's socket path is limited to 107 bytes)."""
    folder = Path(tempfile.mkdtemp(prefix="fwt-", dir="/tmp"))
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture
def waycon_eds(tmp_path: Path) -> Path:
    """The EDS a firmware team would start from (the twin's, exported without its node-ID)."""
    from encoder_conformance.profile.eds import export_eds
    from encoder_conformance.profile.loader import load_profile

    return export_eds(load_profile("waycon-sx").profile, tmp_path / "waycon.eds", None)


def probe_and_run(folder: Path, simulator: str, eds: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    """firmware-ci --probe EDS (no --profile), as the README's probe line: the node-ID given."""
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "ENCODER_CONFORMANCE_VCAN_DIR")}
    return subprocess.run([*PYTHON, "firmware-ci", "--simulator", simulator, "--probe", str(eds), "--node-id", "7",
                           "--history", "off", *extra], cwd=folder, env=env, capture_output=True, text=True,
                          timeout=300)


def test_a_faulty_simulator_fails_on_the_profile_probed_in_the_same_job(tmp_path, waycon_eds):
    """--probe: the profile probed from the simulator firmware-ci started, kept beside the report, is the run's
    profile; the simulator's fault fails the run (1) on it."""
    simulator = twin(tmp_path / "nvm.json", "heartbeat_slow_20pct")
    done = probe_and_run(tmp_path, simulator, waycon_eds, "-k", "heartbeat")
    assert done.returncode == 1, done.stdout[-4000:] + done.stderr[-2000:]
    assert "exit 1: device non-conformant" in done.stderr
    assert "every value written was put back and read back" in done.stdout
    report = tmp_path / "conformance-report"
    assert (report / "probed-profile.yaml").is_file()
    summary = json.loads((report / "run-summary.json").read_text(encoding="utf-8"))
    assert summary["profile_id"] == "probed-profile"
    failed = [result["nodeid"] for result in summary["results"] if result["outcome"] == "failed"]
    assert failed, summary["results"]
    assert all("heartbeat" in nodeid for nodeid in failed), failed


def test_a_probe_whose_simulator_ends_at_reset_node_is_infrastructure(tmp_path, waycon_eds):
    """Without the restart loop the probe's NMT reset node ends the simulator: 69 at once, naming the loop; no
    profile, no run (it had taken 2 min 19 s and ended 0 with a profile of silences)."""
    (tmp_path / "ends_at_reset.py").write_text(ENDS_AT_RESET, encoding="utf-8")
    simulator = f"{sys.executable} ends_at_reset.py 7 {twin(tmp_path / 'nvm.json')}"
    start = time.monotonic()
    done = probe_and_run(tmp_path, simulator, waycon_eds)
    assert done.returncode == 69, done.stdout[-4000:] + done.stderr[-2000:]
    assert "the simulator exited by itself during the probe" in done.stderr
    assert "restarted in a loop" in done.stderr
    assert not (tmp_path / "conformance-report" / "probed-profile.yaml").exists()
    assert not (tmp_path / "conformance-report" / "run-summary.json").exists()
    assert time.monotonic() - start < 30


def test_a_probe_of_a_device_that_vanished_is_no_profile():
    """from-eds --probe on its own (the README's probe line beside a simulator without the loop): a device that no
    longer answers at the end is said, with the loop to use, not written as a profile."""
    import uuid

    from encoder_conformance.cli.probe_outcome import vanished
    from encoder_conformance.config.bus import BusConfig
    from encoder_conformance.probe.findings import Findings
    from encoder_conformance.probe.session import ProbeOptions

    bus = BusConfig({"interface": "virtual", "channel": f"nobody-{uuid.uuid4().hex[:6]}"})
    why = vanished(ProbeOptions(bus, 7, sdo_timeout_s=0.05, boot_timeout_s=0.2), Findings())
    assert why is not None
    assert "node 7 stopped answering during the probe (no boot-up after the probe's NMT reset node)" in why
    assert "restart loop" in why


def test_a_simulator_that_never_answers_is_infrastructure(tmp_path, short_tmp):
    done = firmware_ci(tmp_path, "exec sleep 60", "--boot-timeout", "1", tmp=short_tmp)
    assert done.returncode == 69, done.stdout[-4000:] + done.stderr[-2000:]
    assert "did not answer an SDO read of 1000h" in done.stderr
    assert list(short_tmp.iterdir()) == []  # the state folder is removed, on an error too


def test_a_simulator_that_exits_by_itself_is_named_at_once(tmp_path, short_tmp):
    """CANopenLinux ends its process on NMT reset node: firmware-ci says so (69) as soon as it happened, not after
    the boot time-out, and leaves no state folder behind."""
    start = time.monotonic()
    done = firmware_ci(tmp_path, "sleep 0.2; exit 3", "--boot-timeout", "60", tmp=short_tmp)
    elapsed = time.monotonic() - start
    assert done.returncode == 69, done.stdout[-4000:] + done.stderr[-2000:]
    assert "the simulator exited by itself (exit status 3)" in done.stderr
    assert "a firmware simulator must keep running across NMT reset node (restart it in a loop" in done.stderr
    assert elapsed < 30, f"{elapsed:.1f} s: the boot wait did not notice the simulator had ended"
    assert list(short_tmp.iterdir()) == []


def test_how_a_simulator_exited_is_read_from_its_keeper(tmp_path):
    """The keeper writes the exit status when the simulator ends (negative: the signal that killed it); firmware-ci
    reads it after the boot wait and after the run (where the run's non-zero status becomes 69, naming it)."""
    state = tmp_path / "state"
    state.mkdir()
    (state / fwci.STATE_EXIT).write_text("-11", encoding="utf-8")
    assert fwci._exited_by_itself(state) == "killed by SIGSEGV"
    (state / fwci.STATE_EXIT).write_text("0", encoding="utf-8")
    assert fwci._exited_by_itself(state) == "exit status 0"
    (state / fwci.STATE_EXIT).unlink()
    assert fwci._exited_by_itself(state) is None  # still running


# -- the power switch: power on starts the simulator under a keeper, power off waits for all of it ----------------
def _power(state: Path, action: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*HELPER, "--state", str(state), action], cwd=cwd, capture_output=True, text=True,
                          timeout=30, check=True)


def _wait_for(path: Path, timeout: float = 15.0) -> None:
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path.name} did not appear within {timeout} s"
        time.sleep(0.02)


def _switched(tmp_path: Path, simulator: str) -> Path:
    state = tmp_path / "state"
    state.mkdir()
    (state / fwci.STATE_COMMAND).write_text(simulator, encoding="utf-8")
    (tmp_path / "stand_in.py").write_text(STAND_IN, encoding="utf-8")
    return state


def test_power_off_lets_a_simulator_behind_a_shell_store_at_shutdown(tmp_path):
    """Started through a shell (which does not exec it here): the shell ends at once on SIGTERM; the simulator's
    own shutdown (0.5 s, then it writes its data) is waited for, not cut off by SIGKILL when the shell ends."""
    state = _switched(tmp_path, f"{sys.executable} stand_in.py {tmp_path}; echo ended")
    _power(state, "power-on", tmp_path)
    _wait_for(tmp_path / "up")
    group = int((state / fwci.STATE_PID).read_text(encoding="utf-8"))
    _power(state, "power-off", tmp_path)
    assert (tmp_path / "stored").read_text(encoding="utf-8") == "node-ID 5"
    assert not fwci._group_running(group)
    assert not (state / fwci.STATE_PID).exists()
    assert not (state / fwci.STATE_EXIT).exists()  # ended by the power switch, not by itself


def test_the_readme_restart_loop_survives_reset_node_and_stores_at_power_off(tmp_path):
    """The README's loop: the simulator ends by itself once (NMT reset node) and is started again; power off
    lets it store and does not start it again."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    loop = re.search(r"```sh\n(\s*trap .*?)```", readme, re.S)
    assert loop is not None, "the restart loop example is not in the README"
    script = "\n".join(line.strip() for line in loop.group(1).splitlines())
    assert "./build/fw_sim vcan0" in script
    (tmp_path / "fw_sim_loop.sh").write_text(
        script.replace("./build/fw_sim vcan0", f"{sys.executable} stand_in.py {tmp_path} --reset-once"),
        encoding="utf-8")
    state = _switched(tmp_path, "sh fw_sim_loop.sh")
    _power(state, "power-on", tmp_path)
    _wait_for(tmp_path / "up")  # the second start: the first ended by itself
    assert (tmp_path / "starts").read_text(encoding="utf-8").count("start") == 2
    assert not (state / fwci.STATE_EXIT).exists()  # the loop keeps running
    _power(state, "power-off", tmp_path)
    assert (tmp_path / "stored").read_text(encoding="utf-8") == "node-ID 5"
    assert (tmp_path / "starts").read_text(encoding="utf-8").count("start") == 2  # not started again


def test_power_off_kills_what_does_not_end_in_the_grace_time(tmp_path, monkeypatch):
    state = _switched(tmp_path, "trap '' TERM; sleep 60")
    _power(state, "power-on", tmp_path)
    group = int((state / fwci.STATE_PID).read_text(encoding="utf-8"))
    monkeypatch.setattr(fwci, "STOP_GRACE_S", 0.3)
    start = time.monotonic()
    assert fwci._stop_simulator(state) == 0
    assert time.monotonic() - start < 3
    assert not fwci._group_running(group)


def test_the_run_gets_no_station_history_unless_asked():
    """In a checkout the run would write reports/history.sqlite: a CI job has no use for it."""
    args = argparse.Namespace(profile="p.yaml", can_channel="vcan0", no_power_switch=True)
    command = fwci._run_command(args, ["--node-id", "4"], Path("/r"), [])
    assert command[command.index("--history") + 1] == "off"
    assert command[-2:] == ["--node-id", "4"]
    for given in (["--history", "h.sqlite"], ["--history=h.sqlite"]):
        command = fwci._run_command(args, given, Path("/r"), [])
        assert "off" not in command
        assert command[-len(given) :] == given


@pytest.mark.parametrize("name", ["github", "gitlab"])
def test_example_pipeline_is_printed_valid_and_in_the_readme(name: str, capsys):
    """`firmware-ci --example NAME` prints the shipped file: valid YAML, a firmware-ci line its parser takes, the
    same text as the README shows."""
    import shlex

    import yaml

    from encoder_conformance.cli import firmware_ci
    from encoder_conformance.cli.main import build_parser, main

    assert main(["firmware-ci", "--example", name]) == 0
    text = capsys.readouterr().out
    assert text == (firmware_ci.PIPELINE_DIR / firmware_ci.PIPELINES[name]).read_text(encoding="utf-8")
    assert isinstance(yaml.safe_load(text), dict)
    line = next(part for part in text.splitlines() if "encoder-conformance firmware-ci" in part and "#" not in part)
    words = shlex.split(line[line.index("encoder-conformance") :])[1:]
    args, extra = build_parser().parse_known_args(words)
    assert (args.simulator, args.profile, extra) == ("sh ci/fw_sim_loop.sh", "ci/my-encoder.yaml", ["--node-id", "4"])
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    assert text in readme
    loop = re.search(r"```sh\n(\s*trap .*?)```", readme, re.S)
    assert loop is not None
    for line in loop.group(1).strip().splitlines():  # the loop the pipeline writes is the README's (tested above)
        assert line.strip() in text, line
    assert "placeholder: your simulator's line inside" in text


@pytest.mark.parametrize(("argv", "message"), [
    (["--profile", "waycon-sx", "--probe", "x.eds"], "give --profile or --probe, not both"),
    (["--probe", "no-such.eds"], "--probe no-such.eds: no such file; give the path of your device's EDS"),
], ids=["both", "missing-eds"])
def test_firmware_ci_probe_names_the_option_at_fault(argv, message, capsys):
    from encoder_conformance.cli.main import main

    assert main(["firmware-ci", "--simulator", "./fw_sim vcan0", *argv]) == 4
    assert message in capsys.readouterr().err


def test_firmware_ci_without_simulator_names_what_is_missing(capsys):
    from encoder_conformance.cli.main import main

    assert main(["firmware-ci", "--profile", "waycon-sx"]) == 4
    assert "give --simulator" in capsys.readouterr().err
