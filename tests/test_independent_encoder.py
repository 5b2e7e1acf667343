"""The encoder suites against an encoder that is not our twin: each deliberate fault is caught, none without one.

The twin computes its encoder function with the same reference model the suites take their expectations
from, so a twin run proves little about the suites. ``tests/independent/encoder_device.py`` is a second
reading of CiA 406 and the WDGA manual (python-canopen's LocalNode, an object dictionary from the profile's
EDS, its own arithmetic), in its own process, reached only over a python-can-remote bus; its shaft is turned
by the ``--shaft-drive`` plug-in ``tests.independent.shaft_link``. The suites run against it as against a
bench device (``--can-interface remote``), once conformant and once per break of the device. The
table of outcomes is printed (run with -s). About 35 s.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from encoder_conformance.dut.bench.actuator import ShaftDrivePlugin
from encoder_conformance.runs.session_slots import SESSION_SLOTS
from tests.independent.encoder_function import (
    CamSettings,
    CamSwitch,
    Sensor,
    Units,
    offset_for_preset,
    shown_position,
)

REPO = Path(__file__).resolve().parents[1]
PROFILE = "wachendorff-wdga-mt"
NODE_ID = 5  # not the profile's delivery node-ID (127): the option reaches the device
SUITES = ["suites/test_encoder_position.py", "suites/test_encoder_properties.py", "suites/test_cam.py",
          "suites/test_work_area.py"]
START_TIMEOUT_S = 20.0
RUN_TIMEOUT_S = 120.0

#: each break of the device and the tests that must catch it (fail with the break, pass without): the ones
#: aimed at the broken rule; others fail too (the property test, the CAM tests that move by preset), listed in
#: the printed table
CATCHES = {
    "direction": ["test_encoder_position::test_code_sequence_sets_the_counting_direction"],
    "preset": ["test_encoder_position::test_preset_sets_position_and_offset[middle-cw]",
               "test_encoder_position::test_preset_sets_position_and_offset[top-ccw]",
               "test_encoder_position::test_preset_is_kept_while_the_shaft_turns"],
    "cam-polarity": ["test_cam::test_polarity_inverts_state"],
    "cam-hysteresis": ["test_cam::test_hysteresis_holds_when_leaving_both_directions"],
}
#: modules of the device process: none may import the project (it must be a reading of the texts of its own)
DEVICE_MODULES = ["encoder_device.py", "encoder_function.py", "link.py", "bus_hub.py"]


def _environment() -> dict[str, str]:
    """Without python-can or profile settings from the caller's environment."""
    drop = ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG", "ENCODER_CONFORMANCE_PROFILE",
            "INDEPENDENT_ENCODER_SHAFT")
    return {**{k: v for k, v in os.environ.items() if k not in drop}, "PYTHONUNBUFFERED": "1"}


def _start(args: list[str], log: Path) -> tuple[subprocess.Popen[str], str]:
    """Start ``python -m ARGS``, wait for its READY line; (process, the rest of that line)."""
    stderr = log.open("w", encoding="utf-8")
    process = subprocess.Popen([sys.executable, "-m", *args], cwd=REPO, env=_environment(), text=True,
                               stdout=subprocess.PIPE, stderr=stderr)
    stderr.close()
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.append(process.stdout.readline()), daemon=True)  # type: ignore[union-attr]
    reader.start()
    reader.join(START_TIMEOUT_S)  # the READY line (an empty line if it died first)
    line = lines[0] if lines else ""
    if not line.startswith("READY "):
        _stop(process)
        raise AssertionError(f"{' '.join(args)} did not start:\n{log.read_text(encoding='utf-8')[-3000:]}")
    return process, line.split(" ", 1)[1].strip()


def _stop(process: subprocess.Popen[str]) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=3)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def _outcomes(junit: Path) -> dict[str, str]:
    """'module::test[params]' -> passed / failed / error / skipped."""
    found: dict[str, str] = {}
    for case in ET.parse(junit).getroot().iter("testcase"):
        name = f"{case.get('classname', '').split('.')[-1]}::{case.get('name')}"
        outcome = next((tag for tag in ("failure", "error", "skipped") if case.find(tag) is not None), "passed")
        if found.get(name) in (None, "passed"):  # a teardown error comes as a second case of the same name
            found[name] = {"failure": "failed"}.get(outcome, outcome)
    return found


def _skip_reasons(junit: Path) -> dict[str, str]:
    """'module::test[params]' -> the skip message, for skipped tests."""
    reasons = {}
    for case in ET.parse(junit).getroot().iter("testcase"):
        skipped = case.find("skipped")
        if skipped is not None:
            reasons[f"{case.get('classname', '').split('.')[-1]}::{case.get('name')}"] = skipped.get("message", "")
    return reasons


@dataclass
class Run:
    variant: str
    returncode: int
    outcomes: dict[str, str]
    seconds: float
    output: str
    skip_reasons: dict[str, str] = field(default_factory=dict)

    def with_outcome(self, *outcomes: str) -> set[str]:
        return {name for name, outcome in self.outcomes.items() if outcome in outcomes}


class Bench:
    """The bus, the EDS and a way to run the suites against the device with or without a break."""

    def __init__(self, folder: Path, channel: str, eds: Path) -> None:
        self.folder = folder
        self.channel = channel
        self.eds = eds
        self.runs: dict[str, Run] = {}

    def run(self, variant: str) -> Run:
        """The device started (with ``--break variant`` unless 'conformant'), the suites run, the device stopped."""
        if variant in self.runs:
            return self.runs[variant]
        folder = self.folder / variant
        folder.mkdir()
        device_args = ["tests.independent.encoder_device", "--channel", self.channel, "--node-id", str(NODE_ID),
                       "--eds", str(self.eds)]
        if variant != "conformant":
            device_args += ["--break", variant]
        device, ready = _start(device_args, folder / "device.log")
        try:
            shaft = json.loads(ready)["shaft"]
            command = [sys.executable, "-m", "pytest", *SUITES, "-q", "-p", "no:cacheprovider",
                       "--ec-profile", PROFILE, "--ec-can-interface", "remote", "--ec-can-channel", self.channel,
                       "--ec-node-id", str(NODE_ID), "--ec-allow-destructive",
                       "--ec-shaft-drive", f"tests.independent.shaft_link:drive={shaft}",
                       "--ec-report-dir", str(folder / "report")]
            started = time.monotonic()
            result = subprocess.run(command, cwd=REPO, env=_environment(), text=True, capture_output=True,
                                    timeout=RUN_TIMEOUT_S)
            seconds = time.monotonic() - started
        finally:
            _stop(device)
        junit = folder / "report" / "junit.xml"
        output = result.stdout[-4000:] + result.stderr[-2000:]
        assert junit.exists(), f"{variant}: no junit.xml (exit {result.returncode})\n{output}"
        self.runs[variant] = Run(variant, result.returncode, _outcomes(junit), seconds, output, _skip_reasons(junit))
        return self.runs[variant]


def _bench_with_every_run(folder: Path) -> Bench:
    """The bus hub, the EDS, and the suites run against the conformant device and each break, one after another
    (one device on the bus at a time), holding a session slot (encoder_conformance/runs/session_slots.py)."""
    eds = folder / f"{PROFILE}.eds"
    subprocess.run([sys.executable, "-m", "encoder_conformance", "profile", "to-eds", PROFILE, "-o", str(eds)],
                   cwd=REPO, env=_environment(), check=True, capture_output=True, text=True)
    with SESSION_SLOTS.held():
        hub, channel = _start(["tests.independent.bus_hub"], folder / "bus.log")
        bench = Bench(folder, channel, eds)
        try:
            for variant in ["conformant", *CATCHES]:
                bench.run(variant)
        finally:
            _stop(hub)
    return bench


def sessions_ahead(runs) -> dict:
    """Every run against the independent device (tests/runs_ahead.py)."""
    return {("independent-encoder",): lambda: _bench_with_every_run(runs.mktemp("independent"))}


@pytest.fixture(scope="module")
def bench(runs_ahead) -> Iterator[Bench]:
    made = runs_ahead.results(sessions_ahead(runs_ahead))[("independent-encoder",)]
    yield made
    print(_table(made.runs))


def _table(runs: dict[str, Run]) -> str:
    """Tests that did not pass in some run, one line each: the outcome per run."""
    names = sorted({name for run in runs.values() for name in run.outcomes if run.outcomes[name] != "passed"})
    variants = list(runs)
    lines = ["", "outcomes that were not 'passed' (" + ", ".join(f"{v} {runs[v].seconds:.1f} s" for v in variants)
             + "):", f"{'test':<78} " + " ".join(f"{v[:14]:>14}" for v in variants)]
    for name in names:
        lines.append(f"{name[:78]:<78} " + " ".join(f"{runs[v].outcomes.get(name, '-'):>14}" for v in variants))
    return "\n".join(lines)


def test_conformant_device_passes(bench: Bench):
    """Without a break every encoder test passes or skips as not applicable, and the device is given back."""
    run = bench.run("conformant")
    bad = run.with_outcome("failed", "error")
    assert not bad, f"against the conformant independent device: {sorted(bad)}\n{run.output}"
    assert run.returncode == 0, run.output
    unexplained = {name: why for name, why in run.skip_reasons.items() if "not applicable" not in why}
    assert not unexplained, f"skipped for another reason than the profile (no shaft drive?): {unexplained}"
    for names in CATCHES.values():
        assert set(names) <= run.with_outcome("passed")


@pytest.mark.parametrize("variant", list(CATCHES))
def test_break_is_caught(bench: Bench, variant: str):
    """Each break of the device fails the tests aimed at the rule it breaks, which pass without it."""
    conformant = bench.run("conformant")
    run = bench.run(variant)
    caught = run.with_outcome("failed")
    missed = [name for name in CATCHES[variant] if name not in caught]
    assert not missed, f"--break {variant}: not failed: {missed}\n{run.output}"
    assert run.returncode != 0
    assert set(CATCHES[variant]) <= conformant.with_outcome("passed")


def test_the_device_imports_nothing_of_the_project():
    """The device process is a reading of the texts of its own: no module of it imports encoder_conformance."""
    offenders = []
    for name in DEVICE_MODULES:
        path = REPO / "tests" / "independent" / name
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            modules = [a.name for a in node.names] if isinstance(node, ast.Import) else (
                [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else [])
            offenders += [f"{name}: {m}" for m in modules if m.split(".")[0] in ("encoder_conformance", "fixtures")]
    assert offenders == []


def test_shaft_drive_option_names_what_is_wrong():
    """--shaft-drive: a spec without a factory, a missing module or factory is refused with the form to use."""
    for spec, words in (("tests.independent.shaft_link", "MODULE:FACTORY"), ("no_such_module:drive", "cannot import"),
                        ("tests.independent.shaft_link:nothing", "no callable nothing")):
        with pytest.raises(ValueError, match=words):
            ShaftDrivePlugin.load(spec)
    plugin = ShaftDrivePlugin.load("tests.independent.shaft_link:drive=127.0.0.1:1")
    assert plugin.argument == "127.0.0.1:1"


def test_the_device_function_reproduces_the_manuals_examples():
    """The device's own arithmetic on the WDGA manual's numbers: the 3-cam example (M §12, 4096 steps: 05h at
    0..682, 01h at 683..2048, 02h at 2049..4095) and a preset (M §11.3: the position reads P at once)."""
    cams = CamSettings(0x07, 0x00, (0, 2049, 0, 0, 0, 0, 0, 0), (2048, 4095, 682, 0, 0, 0, 0, 0), (0,) * 8)
    switch = CamSwitch()
    states = {position: switch.update(position, cams) for position in (0, 682, 683, 2048, 2049, 4095)}
    assert states == {0: 0x05, 682: 0x05, 683: 0x01, 2048: 0x01, 2049: 0x02, 4095: 0x02}
    sensor, units = Sensor(16384, 1 << 18), Units(0x04, 4096, 1 << 29, multiturn=True)
    turns = 1234.5678
    offset = offset_for_preset(1000, turns, sensor, units)
    assert shown_position(turns, sensor, units, offset) == 1000
    assert shown_position(turns + 0.25, sensor, units, offset) == 1000 + 1024
