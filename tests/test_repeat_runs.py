"""`encoder-conformance repeat`: the same run several times at once, and what it says about stability."""

from __future__ import annotations

import subprocess
import sys
from collections import Counter

from encoder_conformance.paths import CONTENT_ROOT
from encoder_conformance.runs.fault_matrix import RunResult
from encoder_conformance.runs.repeat import RepeatedRuns, _failure_messages, _measurements

JUNIT = """<testsuites><testsuite>
<testcase classname="suites.test_pdo_timing" name="test_latency">
  <properties><property name="timing latency p99_ms" value="1.250"/><property name="basis" value="cia"/>
  <property name="timing latency limits_ms" value="[.. 10.00] ms"/>
  </properties></testcase>
<testcase classname="suites.test_pdo" name="test_other"><failure message="assert 1 == 2&#10;more">x</failure></testcase>
</testsuite></testsuites>"""


def test_measurements_read_from_junit_properties(tmp_path):
    path = tmp_path / "junit.xml"
    path.write_text(JUNIT, encoding="utf-8")
    assert _measurements(path) == {("test_pdo_timing::test_latency", "latency p99_ms"): 1.25,
                                   ("test_pdo_timing::test_latency", "latency limits_ms"): "[.. 10.00] ms"}


def test_failure_messages_keep_their_first_line(tmp_path):
    path = tmp_path / "junit.xml"
    path.write_text(JUNIT, encoding="utf-8")
    assert _failure_messages(path) == {"test_pdo::test_other": "assert 1 == 2"}


def test_a_test_failing_once_is_failing_and_an_inconclusive_skip_only_unstable():
    runs = [RunResult(None, 0, {"a::t": "passed", "b::t": "passed"}),
            RunResult(None, 1, {"a::t": "failed", "b::t": "skipped"})]
    repeated = RepeatedRuns(runs)
    assert repeated.failing() == {"a::t": Counter(passed=1, failed=1)}
    assert set(repeated.unstable()) == {"a::t", "b::t"}
    assert "tests that failed at least once: 1" in repeated.format()


def test_repeat_command_runs_twice_in_parallel():
    completed = subprocess.run([sys.executable, "-m", "encoder_conformance", "repeat", "--profile", "waycon-sx",
                                "--runs", "2", "-k", "test_heartbeat_frame_format"],
                               cwd=CONTENT_ROOT, capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "2 runs: return codes {0: 2}" in completed.stdout
