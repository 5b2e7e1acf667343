"""suite_runner: a pytest session in a forked child gets the folder and environment asked for, its output is
kept, its exit code returned, and one that hangs is killed after the time-out (as subprocess.run does)."""

from __future__ import annotations

import subprocess

import pytest

from encoder_conformance.runs.suite_runner import run_pytest

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
