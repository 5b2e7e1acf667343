"""``encoder-conformance store``: parameters stored as a factory stores them ("store once" before a firmware CI run),
against an external twin with its memory file: the value written survives a restart of the twin's process only
after the command; a node that does not answer is 69, a profile without a store command a usage error."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from encoder_conformance.cli import main as cli
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.plugin import interrupt
from encoder_conformance.sim.process import start_simulator
from tests.bench_twin import PROFILE, ExternalTwin, start_twin

HEARTBEAT = (0x1017, 0)
NVM_KEY = "0x1017.0"  # the twin's memory file's key of 1017h sub 0


def store(twin: ExternalTwin, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "encoder_conformance", "store", "--profile", PROFILE,
                           "--can-interface", "remote", "--can-channel", twin.channel, *extra],
                          capture_output=True, text=True, timeout=120, check=False)


def test_stored_values_survive_a_restart_of_the_twin(tmp_path: Path):
    twin = start_twin(tmp_path)
    try:
        with twin._client() as node:  # the owner's setting, not stored yet
            node.sdo.download(*HEARTBEAT, (1234).to_bytes(2, "little"))
        assert twin.stored().get(NVM_KEY) != 1234
        wrong = store(twin, "--node-id", str(twin.sim.node_id % 127 + 1))
        assert wrong.returncode == RunExit.COULD_NOT_TEST, wrong.stderr
        assert f"no answer from node {twin.sim.node_id % 127 + 1}" in wrong.stderr
        done = store(twin, "--node-id", str(twin.sim.node_id))
        assert done.returncode == RunExit.PASSED, done.stdout + done.stderr
        assert "1010h.02 'save'" in done.stdout
        assert "confirmed by the device's SDO answer" in done.stdout
        assert "Traceback" not in wrong.stderr + done.stderr
        assert twin.stored()[NVM_KEY] == 1234
    finally:
        twin.close()
    restarted = ExternalTwin(start_simulator(PROFILE, nvm_path=twin.nvm, log_path=tmp_path / "again.log"), twin.nvm,
                             PROFILE)
    try:
        with restarted._client() as node:
            assert int.from_bytes(node.sdo.upload(*HEARTBEAT), "little") == 1234
    finally:
        restarted.close()


def test_a_profile_without_store_command_is_a_usage_error(capsys, monkeypatch):
    monkeypatch.setattr(interrupt, "catch_early", lambda: None)
    status = cli.main(["store", "--profile", "siko-wx58m-1212-mt", "--can-interface", "virtual", "--can-channel",
                       "nobody", "--node-id", "5"])
    assert status == RunExit.USAGE_ERROR
    assert "declares no store command" in capsys.readouterr().err
