"""Conformant variants as a bench meets them: external twins, a stored customer configuration, destructive runs.

Each twin is a separate simulator process playing several open readings at once (encoder_conformance/open_points/)
with the customer's values stored in its memory file, reached only over the bus. One run has no power switch
(a plain adapter), the other the bench's power commands and a shaft drive. Both must pass (exit 0) and give the
device back as found: every value, the whole memory, and every value after a power cycle.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from encoder_conformance.exit_codes import RunExit
from encoder_conformance.runs.session_slots import SESSION_SLOTS
from encoder_conformance.sim.fault_catalogue import VARIANTS
from tests.bench_twin import CUSTOMER_VALUES, REPO, ExternalTwin, as_found_problems, start_twin

#: bench -> the readings its twin plays (each applies to the WDGA; together they touch LSS, SDO, EMCY and PDO)
BENCHES: dict[str, list[str]] = {
    "plain adapter": ["lss_node_id_at_reset_comm", "empty_history_no_data", "comm_error_enters_preoperational",
                      "left_open_transfer_times_out"],
    "power switch and shaft drive": ["lss_unconfigured_waits_for_reset", "pdo_config_refused_in_operational",
                                     "sync_processing_cycle", "interrupt_aborts_open_transfer"],
}


def _command(twin: ExternalTwin, report: Path, with_power: bool) -> list[str]:
    command = [sys.executable, "-m", "encoder_conformance", "run", "--profile", twin.profile, "--can-interface",
               "remote", "--can-channel", twin.channel, "--report-dir", str(report), "--allow-destructive",
               "--history", "off", "-q"]
    if with_power:
        host, port = twin.sim.control
        command += ["--power-off-cmd", twin.power_command("power-off"), "--power-on-cmd",
                    twin.power_command("power-on"), "--power-off-time", "0",
                    "--shaft-drive", f"tests.sim_shaft_drive:drive={host}:{port}"]
    return command


def _bench_run(folder: Path, bench: str) -> dict:
    twin = start_twin(folder / "twin", CUSTOMER_VALUES, variants=BENCHES[bench])
    try:
        before, stored_before = twin.read_everything(), twin.stored()
        env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
        completed = subprocess.run(_command(twin, folder / "report", bench != "plain adapter"), cwd=REPO, env=env,
                                   capture_output=True, text=True, timeout=400)
        return {"returncode": completed.returncode, "output": completed.stdout + completed.stderr,
                "problems": as_found_problems(twin, before, stored_before)}
    finally:
        twin.close()


def _bench_session(folder: Path, bench: str) -> dict:
    """A bench run holding a session slot (encoder_conformance/runs/session_slots.py), as a suite session does."""
    with SESSION_SLOTS.held():
        return _bench_run(folder, bench)


def sessions_ahead(runs) -> dict:
    """Each bench's run (tests/runs_ahead.py)."""
    return {("variant-bench", bench): lambda bench=bench: _bench_session(runs.mktemp(bench.split()[0]), bench)
            for bench in BENCHES}


@pytest.fixture(scope="module")
def bench_runs(runs_ahead) -> dict[str, dict]:
    """Both benches' runs, two at a time (made ahead where they could be)."""
    return {key[1]: run for key, run in runs_ahead.results(sessions_ahead(runs_ahead), workers=2).items()}


def test_the_benches_play_known_variants():
    assert all(variant in VARIANTS for variants in BENCHES.values() for variant in variants)


@pytest.mark.parametrize("bench", list(BENCHES))
def test_conformant_variant_passes_a_destructive_bench_run(bench_runs, bench):
    run = bench_runs[bench]
    assert run["returncode"] == RunExit.PASSED, run["output"][-5000:]
    assert "device restored as found" in run["output"]


@pytest.mark.parametrize("bench", list(BENCHES))
def test_device_left_as_found_values_and_memory(bench_runs, bench):
    problems = bench_runs[bench]["problems"]
    assert problems == [], "the run changed the device:\n" + "\n".join(problems[:20])
