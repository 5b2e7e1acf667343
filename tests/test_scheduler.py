"""The simulator's absolute-deadline scheduler: periods without drift, cancel, robustness.

No sleeps: every test waits on a threading.Event that a job sets. Because the scheduler runs
jobs in deadline order on one thread, a later "sentinel" job proves that every earlier-due
job has had its chance to run.
"""

from __future__ import annotations

import itertools
import logging
import statistics
import threading
import time

import pytest

from encoder_conformance.sim.engine.scheduler import DeadlineScheduler

WAIT_S = 5.0  # generous upper bound for any event; tests end as soon as the event is set


@pytest.fixture
def scheduler():
    sched = DeadlineScheduler(name="test-scheduler")
    yield sched
    sched.stop()


def sentinel(sched: DeadlineScheduler, due: float) -> threading.Event:
    """An event set by a one-shot job at ``due``: once set, every job due earlier has run."""
    done = threading.Event()
    sched.call_at(due, done.set)
    return done


def test_periodic_job_keeps_absolute_deadlines(scheduler):
    """20 periods of 10 ms: never early, mean period within 0.5 ms, no accumulated lateness."""
    period, count = 0.010, 21
    calls: list[float] = []
    done = threading.Event()

    def tick() -> None:
        calls.append(time.monotonic())
        if len(calls) == count:
            done.set()

    start = time.monotonic()
    handle = scheduler.call_at(start + period, tick, period)
    assert done.wait(WAIT_S), f"only {len(calls)} of {count} calls"
    handle.cancel()
    calls = calls[:count]
    for k, t in enumerate(calls):
        assert t >= start + (k + 1) * period, f"call {k} ran {(start + (k + 1) * period - t) * 1e3:.3f} ms early"
    intervals = [b - a for a, b in itertools.pairwise(calls)]
    mean_ms = statistics.fmean(intervals) * 1e3
    assert abs(mean_ms - 10.0) < 0.5, f"mean period {mean_ms:.3f} ms"
    # absolute deadlines: the last call is late only by its own latency, not by 20 accumulated ones
    lateness_ms = (calls[-1] - (start + count * period)) * 1e3
    assert lateness_ms < 5.0, f"last call {lateness_ms:.3f} ms late"


def test_jobs_run_in_deadline_order(scheduler):
    """One-shot jobs added out of order run in the order of their deadlines."""
    order: list[str] = []
    now = time.monotonic()
    scheduler.call_at(now + 0.030, lambda: order.append("c"))
    scheduler.call_at(now + 0.010, lambda: order.append("a"))
    scheduler.call_at(now + 0.020, lambda: order.append("b"))
    assert sentinel(scheduler, now + 0.040).wait(WAIT_S)
    assert order == ["a", "b", "c"]


def test_call_later_runs_once(scheduler):
    """call_later without a period runs exactly once."""
    calls: list[float] = []
    scheduler.call_later(0.005, lambda: calls.append(time.monotonic()))
    assert sentinel(scheduler, time.monotonic() + 0.050).wait(WAIT_S)
    assert len(calls) == 1


def test_cancel_stops_a_periodic_job(scheduler):
    """After cancel() no further calls happen; the handle reports inactive."""
    period = 0.005
    calls: list[float] = []
    third = threading.Event()

    def tick() -> None:
        calls.append(time.monotonic())
        if len(calls) == 3:
            third.set()

    handle = scheduler.call_later(period, tick, period)
    assert handle.active
    assert third.wait(WAIT_S)
    handle.cancel()
    seen = len(calls)
    assert not handle.active
    assert sentinel(scheduler, time.monotonic() + 10 * period).wait(WAIT_S)
    assert len(calls) == seen, f"{len(calls) - seen} call(s) after cancel"


def test_cancel_before_due_prevents_the_call(scheduler):
    """A one-shot job cancelled before its deadline never runs."""
    called = threading.Event()
    handle = scheduler.call_later(0.020, called.set)
    handle.cancel()
    assert sentinel(scheduler, time.monotonic() + 0.040).wait(WAIT_S)
    assert not called.is_set()


def test_cancel_from_inside_the_job(scheduler):
    """A periodic job may cancel itself from its own callback; it then stops."""
    calls: list[int] = []
    holder: dict[str, object] = {}

    def tick() -> None:
        calls.append(1)
        if len(calls) == 2:
            holder["handle"].cancel()  # type: ignore[attr-defined]

    holder["handle"] = scheduler.call_later(0.002, tick, 0.002)
    assert sentinel(scheduler, time.monotonic() + 0.050).wait(WAIT_S)
    assert len(calls) == 2


def test_raising_job_does_not_kill_the_thread(scheduler, caplog):
    """An exception in a job is logged; later jobs and the failing periodic job keep running."""
    failures: list[int] = []
    third_failure = threading.Event()

    def broken() -> None:
        failures.append(1)
        if len(failures) == 3:
            third_failure.set()
        raise RuntimeError("job failed on purpose")

    with caplog.at_level(logging.ERROR, logger="encoder_conformance.sim.engine.scheduler"):
        handle = scheduler.call_later(0.002, broken, 0.002)
        assert third_failure.wait(WAIT_S), "the periodic job stopped after raising"
        handle.cancel()
        after = threading.Event()
        scheduler.call_later(0.001, after.set)
        assert after.wait(WAIT_S), "the scheduler thread died"
    assert any("scheduled job failed" in r.getMessage() for r in caplog.records)


def test_stop_ends_the_thread_and_drops_pending_jobs():
    """stop() returns promptly, the thread ends and pending jobs never run."""
    sched = DeadlineScheduler(name="test-stop")
    called = threading.Event()
    sched.call_later(60.0, called.set)
    sched.stop()
    assert not sched._thread.is_alive()
    assert not called.is_set()
