"""The pytest plugin's option checks: bad options stop the run with one UsageError, no traceback.

Each case is a real ``pytest suites ...`` run from the repository root (subprocess). The runs
are started together by one module fixture so they overlap in time.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from encoder_conformance.sim.fault_catalogue import FAULTS

REPO = Path(__file__).resolve().parents[1]
USAGE_ERROR = int(pytest.ExitCode.USAGE_ERROR)

BAD_PROFILE = """\
schema_version: 1
id: bad-profile
title: Bad
identity: {vendor_name: V, product_name: P, vendor_id: 1, device_type: 0x196, manual: m}
bus: {node_id: 5, bitrate: 250000, bitrates: [250000], node_id_set_by: [fixed], bitrate_set_by: [fixed], manual: m}
capabilities: {cia406: true, heartbeat_producer: true, tpdos: 1, tpdo: 2}
timing: {bootup_max_ms: 500, sdo_response_max_ms: 50}
"""

CASES: dict[str, list[str]] = {
    "unknown-profile": ["--ec-profile", "does-not-exist"],
    "node-id-200": ["--ec-node-id", "200"],
    "unknown-fault": ["--ec-sim-fault", "nonsense"],
    "abstract-profile": ["--ec-profile", "wachendorff-wdga-base"],
    "malformed-profile-file": ["--ec-profile", "{tmp}/bad-profile.yaml"],
}


@dataclass
class Run:
    returncode: int
    stdout: str
    stderr: str
    report_dir: Path

    @property
    def output(self) -> str:
        return self.stdout + self.stderr


def clean_env() -> dict[str, str]:
    """The environment without CAN_* or profile variables that could change the outcome."""
    drop = ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG", "ENCODER_CONFORMANCE_PROFILE")
    return {k: v for k, v in os.environ.items() if k not in drop}


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Run]:
    """Start every case at once, then collect the results."""
    tmp = tmp_path_factory.mktemp("plugin")
    (tmp / "bad-profile.yaml").write_text(BAD_PROFILE, encoding="utf-8")
    started = {}
    for name, args in CASES.items():
        report_dir = tmp / f"reports-{name}"
        command = [sys.executable, "-m", "pytest", "suites", "-p", "no:cacheprovider", "-q",
                   "--ec-report-dir", str(report_dir), *(a.format(tmp=tmp) for a in args)]
        process = subprocess.Popen(command, cwd=REPO, env=clean_env(), text=True,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        started[name] = (process, report_dir)
    results = {}
    for name, (process, report_dir) in started.items():
        try:
            stdout, stderr = process.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            process.kill()
            stdout, stderr = process.communicate()
        results[name] = Run(process.returncode, stdout, stderr, report_dir)
    return results


def check_usage_error(run: Run) -> str:
    """Exit code 4 (usage error), an 'ERROR:' line, no traceback, no tests run; returns the text."""
    assert run.returncode == USAGE_ERROR, f"exit code {run.returncode}\n{run.output[-3000:]}"
    assert "Traceback" not in run.output, run.output[-3000:]
    assert "ERROR: " in run.stderr
    assert " passed" not in run.stdout
    return run.stderr


def test_unknown_profile_is_a_usage_error(runs):
    """--device-profile does-not-exist names the profile and the known ids."""
    text = check_usage_error(runs["unknown-profile"])
    assert "does-not-exist" in text
    assert "wachendorff-wdga-mt" in text


def test_node_id_out_of_range_is_refused(runs):
    """--node-id 200 is refused with the valid range."""
    text = check_usage_error(runs["node-id-200"])
    assert "--node-id 200" in text
    assert "1..127" in text


def test_unknown_fault_is_refused_listing_known_faults(runs):
    """--sim-fault nonsense is refused; the message lists every known fault."""
    text = check_usage_error(runs["unknown-fault"])
    assert "nonsense" in text
    assert all(name in text for name in FAULTS), "not every known fault is listed"


def test_abstract_profile_is_refused(runs):
    """An abstract profile cannot be run; the message says why and what to do."""
    text = check_usage_error(runs["abstract-profile"])
    assert "wachendorff-wdga-base" in text
    assert "abstract" in text
    assert "profile list" in text


def test_malformed_profile_file_names_file_line_and_key(runs):
    """A malformed profile file is a usage error naming file:line and the key path."""
    text = check_usage_error(runs["malformed-profile-file"])
    assert "bad-profile.yaml:6: capabilities.tpdo: unknown key; did you mean 'tpdos'?" in text


def test_usage_errors_write_no_reports(runs):
    """A run refused at configuration leaves no report folder behind."""
    for name, run in runs.items():
        assert not run.report_dir.exists(), f"{name}: {run.report_dir} was created"
