"""How many pytest sessions run at a time in this process, whoever starts them (shared by every pool).

The self-tests start suite sessions from several pools at once (a matrix's workers, and a background pool that
runs the slow modules' sessions ahead while other modules run). Each pool's own size no longer bounds the
machine's load; these slots do. A part of the slots can be reserved for the foreground (the test running now,
which starts processes of its own): background sessions then take only the rest, and a foreground session
waiting for a slot goes before every background one. No library offers a priority semaphore with reservations;
this is a condition variable and four counters.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager


class SessionSlots:
    """At most ``limit`` sessions at a time (None: no limit); background sessions leave the reserved slots free."""

    def __init__(self, limit: int | None = None):
        self._limit = limit
        self._running = 0
        self._reserved = 0
        self._foreground_waiting = 0
        self._depending = 0
        self._changed = threading.Condition()
        self._local = threading.local()

    def set_limit(self, limit: int | None) -> None:
        with self._changed:
            self._limit = limit
            self._changed.notify_all()

    @property
    def running(self) -> int:
        with self._changed:
            return self._running

    def mark_background(self) -> None:
        """This thread's sessions are background ones from now on (a background pool's initializer calls it)."""
        self._local.background = True

    @contextmanager
    def reserved(self, slots: int) -> Iterator[None]:
        """Inside, background sessions leave ``slots`` slots to the foreground (those running go on: a session
        is never interrupted)."""
        with self._changed:
            self._reserved += slots
        try:
            yield
        finally:
            with self._changed:
                self._reserved -= slots
                self._changed.notify_all()

    def is_background(self) -> bool:
        return getattr(self._local, "background", False)

    @contextmanager
    def depending(self) -> Iterator[None]:
        """A foreground thread waits inside for what another thread makes, maybe a background one: reservations do
        not hold meanwhile (a background session the foreground waits for must not wait for a reserved slot). A
        background thread waiting for another changes nothing."""
        if self.is_background():
            yield
            return
        with self._changed:
            self._depending += 1
            self._changed.notify_all()
        try:
            yield
        finally:
            with self._changed:
                self._depending -= 1

    @contextmanager
    def held(self) -> Iterator[None]:
        """One slot for the time of one session."""
        background = self.is_background()
        with self._changed:
            if not background:
                self._foreground_waiting += 1
            try:
                self._changed.wait_for(lambda: self._free(background))
            finally:
                if not background:
                    self._foreground_waiting -= 1
            self._running += 1
        try:
            yield
        finally:
            with self._changed:
                self._running -= 1
                self._changed.notify_all()

    def _free(self, background: bool) -> bool:
        if self._limit is None:
            return True
        if not background:
            return self._running < self._limit
        reserved = 0 if self._depending else self._reserved
        return self._foreground_waiting == 0 and self._running < self._limit - reserved


#: the process's slots (no limit unless a caller sets one: the self-tests do)
SESSION_SLOTS = SessionSlots()
