"""Session slots (encoder_conformance/runs/session_slots.py): a limit over every pool, the foreground first, the
slots a foreground module reserves left free by background sessions."""

from __future__ import annotations

import threading
from pathlib import Path

from encoder_conformance.runs.session_slots import SessionSlots

WAIT_S = 5.0
#: after every other module (tests/conftest.py): the last test asks the process's own slots, which the background's
#: sessions hold while they run (CI, stop 49: its job waited past WAIT_S for a slot they held)
RUNS_LAST = True


def _start(slots: SessionSlots, background: bool, entered: threading.Event, leave: threading.Event) -> threading.Thread:
    def session() -> None:
        if background:
            slots.mark_background()
        with slots.held():
            entered.set()
            leave.wait(WAIT_S)

    thread = threading.Thread(target=session, daemon=True)
    thread.start()
    return thread


def test_no_more_sessions_than_the_limit_whoever_starts_them():
    slots = SessionSlots(2)
    leave = threading.Event()
    entered = [threading.Event() for _ in range(3)]
    threads = []
    for n in range(2):
        threads.append(_start(slots, n == 1, entered[n], leave))
        assert entered[n].wait(WAIT_S)
    threads.append(_start(slots, False, entered[2], leave))
    assert not entered[2].wait(0.2), "a third session started beside two with a limit of 2"
    assert slots.running == 2
    leave.set()
    assert entered[2].wait(WAIT_S)
    for thread in threads:
        thread.join(WAIT_S)
    assert slots.running == 0


def test_a_waiting_foreground_session_goes_before_a_waiting_background_one():
    slots = SessionSlots(1)
    first_leaves, rest_leave = threading.Event(), threading.Event()
    first, background, foreground = threading.Event(), threading.Event(), threading.Event()
    _start(slots, False, first, first_leaves)
    assert first.wait(WAIT_S)
    _start(slots, True, background, rest_leave)
    _start(slots, False, foreground, rest_leave)
    first_leaves.set()
    assert foreground.wait(WAIT_S)
    assert not background.is_set()
    rest_leave.set()
    assert background.wait(WAIT_S)


def test_background_sessions_leave_the_reserved_slots_to_the_foreground():
    slots = SessionSlots(2)
    leave = threading.Event()
    background, foreground = threading.Event(), threading.Event()
    with slots.reserved(1):
        _start(slots, True, background, leave)
        assert background.wait(WAIT_S)
        other = threading.Event()
        _start(slots, True, other, leave)
        assert not other.wait(0.2), "a background session took the reserved slot"
        _start(slots, False, foreground, leave)
        assert foreground.wait(WAIT_S)
    leave.set()
    assert other.wait(WAIT_S)


def test_without_a_limit_nothing_waits():
    slots = SessionSlots()
    leave = threading.Event()
    entered = [threading.Event() for _ in range(5)]
    for event in entered:
        _start(slots, True, event, leave)
    assert all(event.wait(WAIT_S) for event in entered)
    leave.set()


def test_the_foreground_waiting_for_a_background_result_lifts_its_reservation():
    """A background job holds a result's lock while it waits for a slot the foreground reserved; the foreground
    then asks for that result: the reservation must not hold meanwhile (seen: a deadlock in the fault matrix)."""
    from encoder_conformance.runs.session_slots import SESSION_SLOTS
    from tests.suite_session import PARALLEL_RUNS, _Once

    once: _Once[str, int] = _Once(lambda name: Path(name))
    locked = threading.Event()

    def make() -> int:
        locked.set()
        with SESSION_SLOTS.held():
            return 1

    def background() -> None:
        SESSION_SLOTS.mark_background()
        once._once("run", make)

    with SESSION_SLOTS.reserved(PARALLEL_RUNS):
        thread = threading.Thread(target=background, daemon=True)
        thread.start()
        assert locked.wait(WAIT_S)
        result: list[int] = []
        asker = threading.Thread(target=lambda: result.append(once._once("run", lambda: 2)), daemon=True)
        asker.start()
        asker.join(WAIT_S)
    assert result == [1], "the foreground never got the background's result"
