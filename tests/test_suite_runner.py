"""suite_runner: a pytest session in a forked child gets the folder and environment asked for, its output is
kept, its exit code returned, and one that hangs is killed after the time-out (as subprocess.run does); the fork
server preloads no more modules with asserts than it did before SESSION_PRELOAD (pytest rewrites those in a session)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from encoder_conformance.runs.suite_runner import PRELOAD, SESSION_PRELOAD, run_pytest

SESSION = '''
import os
from pathlib import Path

def test_folder_and_environment():
    assert Path.cwd().name == "work"
    assert os.environ["SUITE_RUNNER_PROBE"] == "yes"

def test_fails_on_purpose():
    assert os.environ.get("SUITE_RUNNER_FAIL") != "yes"
'''
HANGING = '''
import threading

def test_hangs():
    threading.Event().wait(60)  # a session that never ends by itself
'''


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "work").mkdir()
    (tmp_path / "work" / "test_probe.py").write_text(SESSION, encoding="utf-8")
    (tmp_path / "work" / "test_hang.py").write_text(HANGING, encoding="utf-8")
    return tmp_path / "work"


def test_session_gets_folder_and_environment(folder):
    env = {"PATH": "/usr/bin:/bin", "SUITE_RUNNER_PROBE": "yes"}
    result = run_pytest(["test_probe.py", "-q", "-p", "no:cacheprovider"], folder, folder / "out.txt", 60, env)
    assert result.returncode == 0, result.output
    assert "2 passed" in result.output
    assert (folder / "out.txt").read_text(encoding="utf-8") == result.output


def test_failing_session_returns_its_exit_code(folder):
    env = {"SUITE_RUNNER_PROBE": "yes", "SUITE_RUNNER_FAIL": "yes"}
    result = run_pytest(["test_probe.py", "-q", "-p", "no:cacheprovider"], folder, folder / "out.txt", 60, env)
    assert result.returncode == 1
    assert "1 failed, 1 passed" in result.output


def test_hanging_session_is_killed_after_the_timeout(folder):
    with pytest.raises(subprocess.TimeoutExpired):
        run_pytest(["test_hang.py", "-q", "-p", "no:cacheprovider"], folder, folder / "out.txt", 3)


#: modules with assert statements, of distributions pytest rewrites (their pytest11 plugins), that the fork server
#: imported before SESSION_PRELOAD came: the profile schema and the device's and twin's modules, which the command
#: line (the profile) or the twin imports before pytest too
UNREWRITTEN_BEFORE = {
    "encoder_conformance.profile.schema", "encoder_conformance.profile.value_domain",
    "encoder_conformance.dut.nmt.nmt_states", "encoder_conformance.dut.sdo.sdo_client",
    "encoder_conformance.dut.custody.write_plan", "encoder_conformance.sim.process",
    "encoder_conformance.sim.engine.encoder", "encoder_conformance.sim.engine.timer_link"}
_WITH_ASSERTS = """
import importlib, json, re, sys
for name in sys.argv[1:]:
    importlib.import_module(name)
def asserts(module):
    path = getattr(module, "__file__", None) or ""
    return path.endswith(".py") and re.search(r"^\\s*assert\\b", open(path, encoding="utf-8").read(), re.M)
rewritten = ("encoder_conformance", "_hypothesis_pytestplugin", "pytest_html", "pytest_metadata")
print(json.dumps(sorted(n for n, m in list(sys.modules.items()) if n.startswith(rewritten) and asserts(m))))
"""


def test_the_session_preload_leaves_asserts_to_pytest():
    """A module whose asserts pytest rewrites in a user's session (the suite helpers' checks, the custody, the LSS
    steps) is not imported by the fork server's SESSION_PRELOAD: a failing assert there reads as in a user's run."""
    done = subprocess.run([sys.executable, "-c", _WITH_ASSERTS, *PRELOAD], capture_output=True, text=True,
                          timeout=120, check=True)
    assert set(json.loads(done.stdout)) <= UNREWRITTEN_BEFORE
    assert set(SESSION_PRELOAD) <= set(PRELOAD)
