"""A device on a bench belongs to someone: the run against an external twin that holds a customer's
stored configuration (tests/bench_twin.py), as a bench engineer runs it.

- a complete --allow-destructive run leaves every value and the whole memory as found, also after
  a power cycle, and passes everything a twin in factory state passes;
- Ctrl-C at any moment (1-12 s, inside the factory-state preparation and a store test's power cycle)
  ends the run within 2 s with exit 130 and nothing left changed, in use or stored; two runs at a
  time, a busy process spinning from just before each Ctrl-C until that run has ended;
- a run killed hard (SIGKILL) is finished by ``encoder-conformance restore --from`` its snapshot;
- a device killed or frozen mid-run ends the run with one reason and exit code 69 within 5 s, no
  traceback; an endpoint that accepts the connection and never answers: a start-up error within 10 s.
"""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
from bench_twin import CUSTOMER_VALUES, REPO, as_found_problems, start_twin, wait_for_line

from encoder_conformance.dut.link.connection import OPEN_TIMEOUT_S
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.runs.host_load import BusyGate
from encoder_conformance.runs.session_slots import SESSION_SLOTS
from tests.suite_session import PARALLEL_RUNS

#: seconds after the start of the run at which Ctrl-C arrives (the suites start about 1.5 s in)
INTERRUPT_AT_S = [1.0, 2.0, 3.0, 4.5, 6.0, 7.5, 9.0]  # 10.5 s and 12 s came after the end of faster runs
#: and as soon as a test reports its result (pytest -v prints the line at the end of a test), i.e. inside
#: the next one: the factory-state preparation (1011h 'load' + reset), the power cycle of a stored value,
#: and the LSS unconfigured start-up (the WDGA stores node-ID 255 and is power-cycled to apply it)
INTERRUPT_AFTER = ["test_object_dictionary.py::test_undeclared_subindex_aborts",
                   "test_store_restore.py::test_stored_value_survives_reset_node",
                   "test_lss.py::test_configured_device_not_identified_as_non_configured"]
STORE_POWER_CYCLE, LSS_UNCONFIGURED = INTERRUPT_AFTER[1:3]
MOMENTS: list[float | str] = [*INTERRUPT_AT_S, *INTERRUPT_AFTER]
#: no background session starts while this module runs (tests/runs_ahead.py): it times Ctrl-C beside a busy
#: process of its own, and its fixtures run two destructive runs at a time
FOREGROUND_SLOTS = PARALLEL_RUNS
#: after every other module (tests/conftest.py): its Ctrl-C runs are timed, best when the background is done
RUNS_LAST = True
CTRL_C_LIMIT_S = 2.0  # the run's own clock, interrupt to verdict (run-outcome.json stopped_after_s)
#: what this harness measures on top (process exit, its own wake-up beside a busy process): CI saw 2.08 s
#: from send_signal to communicate() for a run that stopped in time
HARNESS_MARGIN_S = 0.5
LOST_LIMIT_S = 5.0
#: the busy process spins this long before a Ctrl-C at a time (before one after a test's line: from that line on)
BUSY_LEAD_S = 0.5


def _outcomes(junit: Path) -> dict[str, str]:
    outcomes = {}
    for case in ET.parse(junit).getroot().iter("testcase"):
        kind = next((child.tag for child in case if child.tag in ("failure", "error", "skipped")), "passed")
        outcomes[f"{case.get('classname')}::{case.get('name')}"] = kind
    return outcomes


def _full_run(folder: Path, customer: dict | None) -> dict:
    twin = start_twin(folder, customer)
    try:
        before, stored_before = twin.read_everything(), twin.stored()
        run = twin.start_run(folder / "report", "-q")
        output, _ = run.communicate(timeout=300)
        return {"returncode": run.returncode, "output": output, "outcomes": _outcomes(folder / "report" / "junit.xml"),
                "problems": as_found_problems(twin, before, stored_before), "stored_before": stored_before}
    finally:
        twin.close()


def sessions_ahead(runs) -> dict:
    """The runs whose checks take no time limit (tests/runs_ahead.py): the complete destructive runs and the hard
    crashes with their restore. The Ctrl-C runs stay here: they time the stop beside a busy process of their own."""
    jobs = {("bench-safety", "destructive", name): lambda name=name, values=values: _held(
                _full_run, runs.mktemp(name), values) for name, values in (("customer", CUSTOMER_VALUES),
                                                                           ("factory", None))}
    for after in (STORE_POWER_CYCLE, LSS_UNCONFIGURED):
        jobs[("bench-safety", "crash", after)] = lambda after=after: _held(_crash_and_restore, runs.mktemp("crash"),
                                                                            after)
    return jobs


def _held(run: Callable[..., dict], *args: Any) -> dict:
    """``run(*args)`` holding a session slot (encoder_conformance/runs/session_slots.py), as a suite session does."""
    with SESSION_SLOTS.held():
        return run(*args)


@pytest.fixture(scope="module")
def bench_runs(runs_ahead) -> dict[tuple[str, str], dict]:
    """The destructive runs ("destructive", "customer"/"factory") and the hard crashes ("crash", the test after
    whose line the run is killed), two at a time, most made ahead."""
    return {key[1:]: run for key, run in runs_ahead.results(sessions_ahead(runs_ahead), workers=2).items()}


@pytest.fixture(scope="module")
def destructive_runs(bench_runs) -> dict[str, dict]:
    """A complete destructive run against a twin with a customer configuration and one in factory state."""
    return {name: bench_runs[("destructive", name)] for name in ("customer", "factory")}


def test_destructive_run_leaves_the_customer_configuration(destructive_runs):
    """All five stored customer values, the whole memory and every value as found, also after a power cycle."""
    run = destructive_runs["customer"]
    for (index, sub), value in CUSTOMER_VALUES.items():
        assert run["stored_before"][f"0x{index:04X}.{sub}"] == value
    assert not run["problems"], "the run changed the device:\n" + "\n".join(run["problems"][:20])
    assert "device restored as found" in run["output"]


def test_stored_configuration_passes_what_factory_state_passes(destructive_runs):
    """A device with a stored configuration passes every test a factory-state device passes."""
    customer, factory = destructive_runs["customer"], destructive_runs["factory"]
    assert factory["returncode"] == RunExit.PASSED, factory["output"][-3000:]
    assert customer["returncode"] == RunExit.PASSED, customer["output"][-3000:]
    lost = [t for t, o in factory["outcomes"].items() if o == "passed" and customer["outcomes"].get(t) != "passed"]
    assert not lost, f"pass in factory state, not with the customer's configuration: {lost}"


def _up_to(at: float | str) -> list[str]:
    """A run's selection for a moment: the whole suite for a moment in time; for the moment after a test's line,
    that test's module only (the signal lands in the module's next test all the same; the modules before it took
    ~30 s of each such run and prove nothing about the moment)."""
    return [] if isinstance(at, float) else ["-k", at.split(".py::")[0]]


def _interrupted_run(folder: Path, at: float | str, busy: BusyGate) -> dict:
    """Start a run, send SIGINT at ``at`` seconds (or when that test starts), check the device afterwards. The
    busy process spins from just before the signal until the run has ended (what the 2 s bound is about)."""
    twin = start_twin(folder, CUSTOMER_VALUES)
    try:
        before, stored_before = twin.read_everything(), twin.stored()
        run = twin.start_run(folder / "report", "-v", *_up_to(at))
        seen: list[str] = []
        if isinstance(at, str):
            assert wait_for_line(run, at, 120, seen), f"{at} never ended:\n{''.join(seen[-20:])}"
        else:
            threading.Event().wait(at - BUSY_LEAD_S)
        with busy.held():
            threading.Event().wait(0.05 if isinstance(at, str) else BUSY_LEAD_S)  # a line: inside the next test
            sent = time.monotonic()
            ended_before = run.poll() is not None
            run.send_signal(signal.SIGINT)
            output, _ = run.communicate(timeout=30)
            ended = time.monotonic() - sent
        outcome_file = folder / "report" / "run-outcome.json"
        outcome = json.loads(outcome_file.read_text(encoding="utf-8")) if outcome_file.exists() else {}
        return {"returncode": run.returncode, "seconds": ended, "output": "".join(seen) + output,
                "problems": as_found_problems(twin, before, stored_before), "ended_before": ended_before,
                "outcome": outcome}
    finally:
        twin.close()



@pytest.fixture(scope="module")
def interrupted_runs(tmp_path_factory) -> dict[float | str, dict]:
    """Each moment a run of its own against a twin of its own, two at a time; a busy process spins around each
    Ctrl-C (BusyGate: one core, held by either run; beside the whole fixture it stretched the runs' way to their
    moments and the as-found reads, and their length varied by tens of seconds)."""
    with BusyGate() as busy, ThreadPoolExecutor(max_workers=2) as pool:
        futures = {at: pool.submit(_interrupted_run, tmp_path_factory.mktemp("sigint"), at, busy) for at in MOMENTS}
        return {at: future.result() for at, future in futures.items()}


@pytest.mark.parametrize("at", MOMENTS, ids=str)
def test_ctrl_c_ends_within_2_s_and_leaves_nothing_changed(interrupted_runs, at):
    run = interrupted_runs[at]
    assert not run["ended_before"], f"the run had ended before the signal at {at}: the moment proves nothing"
    assert run["returncode"] == RunExit.INTERRUPTED, run["output"][-3000:]
    own = run["outcome"].get("stopped_after_s")  # None: the signal came before the session (start-up)
    if run["outcome"].get("interrupted"):
        assert own is not None, f"an interrupted run without its stop time: {run['outcome']}"
        assert own < CTRL_C_LIMIT_S, f"the run took {own:.2f} s from Ctrl-C to its verdict"
    assert run["seconds"] < CTRL_C_LIMIT_S + HARNESS_MARGIN_S, f"ended {run['seconds']:.2f} s after Ctrl-C"
    assert not run["problems"], "left changed:\n" + "\n".join(run["problems"][:20]) + run["output"][-2000:]


def test_ctrl_c_figures_printed(interrupted_runs, capsys):
    """For the notes: how long after Ctrl-C each run ended."""
    with capsys.disabled():
        print("\nCtrl-C moment -> exit code, seconds until the run ended:")
        for at, run in interrupted_runs.items():
            print(f"  {at!s:62s} {run['returncode']:4d} {run['seconds']:5.2f} s")
    assert len(interrupted_runs) == len(MOMENTS)


def _crash_and_restore(folder: Path, after: str) -> dict:
    """A run killed (SIGKILL) after ``after``'s line, then 'restore --from' its snapshot with the bench's power
    commands; what came of it and what is left changed."""
    twin = start_twin(folder / "twin", CUSTOMER_VALUES)
    try:
        before, stored_before = twin.read_everything(), twin.stored()
        run = twin.start_run(folder / "report", "-v", *_up_to(after))
        seen: list[str] = []
        reached = wait_for_line(run, after, 120, seen)
        if not reached:
            run.kill()
            run.communicate(timeout=10)
            return {"reached": False, "seen": "".join(seen[-20:])}
        threading.Event().wait(0.05)
        run.kill()
        run.communicate(timeout=10)
        snapshot = folder / "report" / "device-snapshot.json"
        if not snapshot.exists():
            return {"reached": True, "snapshot": False}
        restore = subprocess.run([sys.executable, "-m", "encoder_conformance", "restore", "--from", str(snapshot),
                                  "--can-interface", "remote", "--can-channel", twin.channel,
                                  "--power-on-cmd", twin.power_command("power-on"),
                                  "--power-off-cmd", twin.power_command("power-off")],
                                 cwd=REPO, capture_output=True, text=True, timeout=120)
        return {"reached": True, "snapshot": True, "returncode": restore.returncode,
                "output": restore.stdout + restore.stderr, "problems": as_found_problems(twin, before, stored_before)}
    finally:
        twin.close()


@pytest.mark.parametrize("after", [STORE_POWER_CYCLE, LSS_UNCONFIGURED], ids=["store power cycle", "LSS node-ID 255"])
def test_restore_command_finishes_after_a_hard_crash(bench_runs, after):
    """SIGKILL during the power cycle of the store/restore suite, or while the LSS suite has made the device
    unconfigured (node-ID 255 stored); 'restore --from' the snapshot (with the bench's power commands) gives
    the node-ID back by LSS and puts everything back."""
    crash = bench_runs[("crash", after)]
    assert crash["reached"], crash.get("seen")
    assert crash["snapshot"], "no device-snapshot.json"
    assert crash["returncode"] == RunExit.PASSED, crash["output"]
    assert "device restored as found" in crash["output"]
    assert not crash["problems"], "left changed:\n" + "\n".join(crash["problems"][:20])


def _lost_device_run(folder: Path, how: str) -> tuple[subprocess.CompletedProcess[str], float]:
    twin = start_twin(folder)
    try:
        run = twin.start_run(folder / "report", "-v")
        seen: list[str] = []
        # mid-run means after the first verdict, not a fixed delay: a loaded CI machine can still be starting up
        assert wait_for_line(run, " PASSED", 120, seen), "".join(seen[-20:])
        gone = time.monotonic()
        twin.kill() if how == "killed" else twin.freeze()
        output, _ = run.communicate(timeout=60)
        return subprocess.CompletedProcess(run.args, run.returncode, "".join(seen) + output), time.monotonic() - gone
    finally:
        twin.close()


#: how the device went -> the run's exit code. Killed, its endpoint (the bench's adapter) closes: the bus is lost
#: and nothing about the device is shown (could not test). Frozen, the bus stays up and the device stops
#: answering in the middle of a test: that test fails, naming the last frames sent (device FAIL).
LOST_EXIT = {"killed": (RunExit.COULD_NOT_TEST, "could not test:"), "frozen": (RunExit.NON_CONFORMANT,
                                                                            "the device stopped answering")}


@pytest.mark.parametrize("how", ["killed", "frozen"])
def test_device_gone_mid_run_is_one_reason_not_hundreds_of_failures(tmp_path, how):
    completed, seconds = _lost_device_run(tmp_path, how)
    output = completed.stdout
    code, reason = LOST_EXIT[how]
    assert completed.returncode == code, output[-3000:]
    assert seconds < LOST_LIMIT_S, f"the run ended {seconds:.1f} s after the device was {how}"
    assert "Traceback" not in output
    assert "BrokenPipeError" not in output
    assert 1 <= output.count(reason) <= 4, output[-3000:]  # the test, the summary, the stop line: not hundreds
    assert "test(s) not run" in output
    assert "NOT RESTORED" in output
    assert "restore --from" in output


def _run_against_endpoint(port: int, report_dir: Path) -> tuple[subprocess.CompletedProcess[str], float]:
    """A run whose bus is the websocket endpoint at ``port`` on loopback; its result and wall seconds."""
    start = time.monotonic()
    completed = subprocess.run(
        [sys.executable, "-m", "encoder_conformance", "run", "--can-interface", "remote", "--can-channel",
         f"ws://127.0.0.1:{port}/", "--report-dir", str(report_dir), "-q"],
        cwd=REPO, capture_output=True, text=True, timeout=60)
    return completed, time.monotonic() - start


def test_endpoint_that_never_answers_is_a_start_up_error(tmp_path):
    """A TCP endpoint that accepts and stays silent: one start-up error, exit 69, and it costs no more than the
    open bound (OPEN_TIMEOUT_S) beyond what the same run costs against a port that refuses at once (the process's
    own start, measured beside it: a fixed bound failed on a loaded CI host at 10.3 s)."""
    closed = socket.socket()
    closed.bind(("127.0.0.1", 0))
    refused_port = closed.getsockname()[1]
    closed.close()  # nothing listens there now: the connection is refused at once
    refused, refused_s = _run_against_endpoint(refused_port, tmp_path / "refused")
    assert refused.returncode == RunExit.COULD_NOT_TEST, refused.stdout[-2000:]
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    accepted: list[socket.socket] = []
    threading.Thread(target=lambda: accepted.append(server.accept()[0]), daemon=True).start()
    port = server.getsockname()[1]
    try:
        completed, seconds = _run_against_endpoint(port, tmp_path / "report")
    finally:
        server.close()
        for conn in accepted:
            conn.close()
    assert completed.returncode == RunExit.COULD_NOT_TEST, completed.stdout[-2000:]
    assert seconds < refused_s + OPEN_TIMEOUT_S + 2.0, \
        f"took {seconds:.1f} s; against a refusing port {refused_s:.1f} s, open bound {OPEN_TIMEOUT_S:.0f} s"
    assert "did not open within" in completed.stdout
    assert "Traceback" not in completed.stdout + completed.stderr
