"""The live progress line: its text, when it shows, and that it stays out of captured output and reports.

The formatting and the drawing are unit-tested with a pipe and a fake clock; one small run on a pseudo
terminal shows the line, one without a terminal shows none of it (and simulator.log is filled).
"""

from __future__ import annotations

import os
import pty
import re
import select
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from encoder_conformance.plugin import progress
from encoder_conformance.plugin.progress import CLEAR, LiveProgress, Tally, format_line

REPO = Path(__file__).resolve().parents[1]
SMALL_RUN = ["-m", "encoder_conformance", "run", "--profile", "waycon-sx", "-k", "test_identity"]


def test_the_line_names_area_count_elapsed_and_remaining():
    tally = Tally(total=200, started=51, finished=50, area="PDO", failed=2, warnings=1)
    line = format_line(tally, elapsed_s=100.0, width=200)
    assert line.startswith("PDO  test 51 of 200  1:40 elapsed")
    assert "~5:00 left" in line  # 2 s per test so far, 150 to go
    assert line.endswith("2 failed, 1 warnings")


def test_no_estimate_before_three_tests_have_ended():
    assert "estimating" in format_line(Tally(total=10, started=2, finished=1, area="SDO"), 3.0, 200)


def test_the_line_fits_the_terminal():
    line = format_line(Tally(total=10, started=2, finished=1, area="encoder function"), 3.0, 20)
    assert len(line) < 20
    assert line.endswith("…")


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def read_all(fd: int) -> str:
    chunks = []
    while select.select([fd], [], [], 0)[0]:
        data = os.read(fd, 65536)
        if not data:
            break
        chunks.append(data)
    return b"".join(chunks).decode()


def test_drawn_only_after_a_few_seconds_and_erased_at_the_end():
    read_end, write_end = os.pipe()
    clock = FakeClock()
    live = LiveProgress(write_end, lambda: 120, clock=clock)
    live.tally.total = 3  # begin() without its clock thread
    live.test_started("suites/test_nmt.py::test_start")
    assert read_all(read_end) == ""  # a short run never shows it
    clock.now = 5.0
    live.test_finished()
    live.test_started("suites/test_pdo.py::test_sync")
    shown = read_all(read_end)
    assert shown.startswith(CLEAR)
    assert "PDO  test 2 of 3  0:05 elapsed" in shown
    failed = SimpleNamespace(failed=True, skipped=False, nodeid="suites/test_pdo.py::test_sync", when="call",
                             user_properties=[])
    live.test_reported(failed)  # type: ignore[arg-type]
    above = read_all(read_end)
    assert f"{CLEAR}FAILED suites/test_pdo.py::test_sync\n" in above
    assert above.rstrip().endswith("1 failed")  # the line comes back below it
    live.close()
    assert read_all(read_end) == CLEAR
    os.close(read_end)


@pytest.mark.parametrize(("isatty", "environ", "verbosity", "shown"), [
    (True, {}, 0, True),
    (False, {}, 0, False),
    (True, {"CI": "true"}, 0, False),
    (True, {"ENCODER_CONFORMANCE_PROGRESS": "0"}, 0, False),
    (True, {}, 1, False),
    (True, {}, -1, False),
], ids=["terminal", "not-a-terminal", "ci", "switched-off", "verbose", "quiet"])
def test_shown_only_where_a_person_watches(monkeypatch, isatty, environ, verbosity, shown):
    monkeypatch.setattr(progress, "runs_suites", lambda config: True)
    config = SimpleNamespace(get_verbosity=lambda: verbosity,
                             pluginmanager=SimpleNamespace(get_plugin=lambda name: object()))
    assert progress.wanted(config, isatty, environ) is shown  # type: ignore[arg-type]


def _environment(**extra: str) -> dict[str, str]:
    env = {key: value for key, value in os.environ.items() if key != "CI"}
    return {**env, **extra}


def test_a_run_on_a_terminal_shows_the_line_and_keeps_it_out_of_the_reports(tmp_path):
    """On a (pseudo) terminal: the line instead of dots; junit.xml and the captured output hold none of it."""
    controller, terminal = pty.openpty()
    process = subprocess.Popen([sys.executable, *SMALL_RUN, "--report-dir", str(tmp_path)], cwd=REPO,
                               stdin=subprocess.DEVNULL, stdout=terminal, stderr=terminal,
                               env=_environment(ENCODER_CONFORMANCE_PROGRESS="always", COLUMNS="200"))
    os.close(terminal)
    output = bytearray()
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if select.select([controller], [], [], 1.0)[0]:
            try:
                data = os.read(controller, 65536)
            except OSError:  # the run ended and closed the terminal
                break
            if not data:
                break
            output += data
        elif process.poll() is not None:
            break
    os.close(controller)
    assert process.wait(timeout=30) == 0, output.decode(errors="replace")[-3000:]
    text = output.decode(errors="replace")
    assert "identity  test 1 of" in text
    assert " elapsed" in text
    assert not re.search(r"test_identity\.py [.sF]+", text)  # no dots while the line shows
    for report in ("junit.xml", "report.html"):
        assert " elapsed" not in (tmp_path / report).read_text(encoding="utf-8")


def test_a_run_without_a_terminal_prints_no_progress_and_fills_the_simulator_log(tmp_path):
    """Output to a pipe (CI, a log file): pytest's usual dots, none of the line. The simulator's log names the
    profile and what happened to the device."""
    result = subprocess.run([sys.executable, *SMALL_RUN, "--report-dir", str(tmp_path)], cwd=REPO,
                            capture_output=True, text=True, timeout=180, env=_environment())
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]
    assert "\x1b[K" not in result.stdout
    assert " elapsed" not in result.stdout
    assert re.search(r"suites/test_identity\.py [.sF]+ ", result.stdout)  # pytest's dots
    log = (tmp_path / "simulator.log").read_text(encoding="utf-8")
    assert "profile waycon-sx" in log
    assert "NMT state pre-operational" in log
    assert "stopping" in log
