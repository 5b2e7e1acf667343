"""``encoder-conformance firmware-ci``: the loop a firmware team's CI runs, with the built-in twin in the role of
the firmware simulator (a process on a SocketCAN channel; here the user-space bus, as in a container).

A conformant simulator passes (0) with its artifacts in the report folder and its process restarted by the power
switch; a faulty one fails (1); one that never answers is infrastructure (69), not a verdict on the firmware.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from encoder_conformance.vcan import BuildError, library

PYTHON = [sys.executable, "-m", "encoder_conformance"]
REPO = Path(__file__).resolve().parents[1]

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


def firmware_ci(folder: Path, simulator: str, *extra: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "ENCODER_CONFORMANCE_VCAN_DIR")}
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


def test_a_faulty_simulator_fails(tmp_path):
    done = firmware_ci(tmp_path, twin(tmp_path / "nvm.json", "heartbeat_slow_20pct"), "-k", "heartbeat")
    assert done.returncode == 1, done.stdout[-4000:] + done.stderr[-2000:]
    assert "exit 1: device non-conformant" in done.stderr


def test_a_simulator_that_never_answers_is_infrastructure(tmp_path):
    done = firmware_ci(tmp_path, "exec sleep 60", "--boot-timeout", "1")
    assert done.returncode == 69, done.stdout[-4000:] + done.stderr[-2000:]
    assert "did not answer an SDO read of 1000h" in done.stderr


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
    assert (args.simulator, args.profile, extra) == ("./build/fw_sim vcan0", "ci/my-encoder.yaml", [])
    assert text in (REPO / "README.md").read_text(encoding="utf-8")


def test_firmware_ci_without_simulator_names_what_is_missing(capsys):
    from encoder_conformance.cli.main import main

    assert main(["firmware-ci", "--profile", "waycon-sx"]) == 4
    assert "give --simulator" in capsys.readouterr().err
