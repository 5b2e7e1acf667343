"""Ctrl-C and SIGTERM: stop the tests at once, give the device back first, end within 2 s.

The first signal stops the tests (KeyboardInterrupt in the main thread, as Python's default
handler does) and tells the device layer that the run is stopping, so no test clean-up races the
restore. While the restore runs (``shielded``), further signals only print what is going on; a
third one abandons the restore. A watchdog ends the process if anything still blocks after
``HARD_LIMIT_S``: Ctrl-C always ends the run.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any, TypeAlias

from encoder_conformance.exit_codes import interrupted_by

#: the restore's share of the 2 s a Ctrl-C may take (the rest: reports, bus and simulator shutdown)
RESTORE_BUDGET_S = 1.2
HARD_LIMIT_S = 1.95
SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: what signal.signal takes and gives back: a function, SIG_DFL/SIG_IGN, or None (a handler not set from Python)
SignalHandler: TypeAlias = Callable[[int, FrameType | None], Any] | int | signal.Handlers | None

#: signals that arrived before the run's guard was installed (``catch_early``): a KeyboardInterrupt raised
#: while the interpreter runs a finaliser or a callback during start-up is printed and dropped, and the run
#: went on to its end with exit code 0 (seen once in CI: Ctrl-C 1.0 s into a loaded run)
EARLY_SIGNALS: list[int] = []


def catch_early() -> None:
    """Record SIGINT/SIGTERM from now on (and raise KeyboardInterrupt, as Python does) until the guard takes
    over; the guard then stops the run if one came. Called first thing by the command line."""
    def record(signum: int, frame: FrameType | None) -> None:
        EARLY_SIGNALS.append(signum)
        raise KeyboardInterrupt

    if threading.current_thread() is threading.main_thread():
        for sig in SIGNALS:
            signal.signal(sig, record)


class InterruptGuard:
    """Turns SIGINT/SIGTERM into an orderly stop of the run."""

    def __init__(self, on_stop: Callable[[str], None]) -> None:
        self._on_stop = on_stop
        self.signum: int | None = None
        self.at: float | None = None
        self._shielded = 0
        self._count = 0
        self._previous: dict[int, SignalHandler] = {}
        self._stderr: int | None = None  # the real stderr: pytest redirects fd 2 while a test runs

    @property
    def exit_code(self) -> int | None:
        return None if self.signum is None else interrupted_by(self.signum)

    @property
    def reason(self) -> str:
        name = signal.Signals(self.signum).name if self.signum else "?"
        return f"interrupted ({name})"

    def install(self) -> None:
        if threading.current_thread() is not threading.main_thread():
            return  # signals reach only the main thread (pytest-xdist workers and the like)
        with contextlib.suppress(OSError):
            self._stderr = os.dup(2)
        for sig in SIGNALS:
            self._previous[sig] = signal.signal(sig, self._handle)
        if EARLY_SIGNALS:  # a Ctrl-C came during start-up and was lost on the way: stop now
            self._handle(EARLY_SIGNALS[0], None)

    def uninstall(self) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous.clear()
        if self._stderr is not None:
            with contextlib.suppress(OSError):
                os.close(self._stderr)
            self._stderr = None

    def since_interrupt(self) -> float | None:
        """Seconds since the first signal (None without one)."""
        return None if self.at is None else round(time.monotonic() - self.at, 3)

    def remaining(self) -> float:
        """Seconds left of the restore budget since the first signal (inf without one)."""
        if self.at is None:
            return float("inf")
        return max(0.0, RESTORE_BUDGET_S - (time.monotonic() - self.at))

    @contextmanager
    def shield(self) -> Iterator[None]:
        """While inside, a signal does not raise: the restore finishes within its own deadline."""
        self._shielded += 1
        try:
            yield
        finally:
            self._shielded -= 1

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        self._count += 1
        if self.signum is None:
            self.signum, self.at = signum, time.monotonic()
            self._on_stop(self.reason)
            watchdog = threading.Timer(HARD_LIMIT_S, self._hard_exit)
            watchdog.daemon = True
            watchdog.start()
            self.say(f"\n{self.reason}: stopping the tests, putting the device back as found ...")
            if not self._shielded:
                raise KeyboardInterrupt
            return
        if self._count >= 3 and self._shielded:
            self.say("third interrupt: abandoning the restore (the device may be left changed; see the snapshot)")
            raise KeyboardInterrupt
        self.say(f"still putting the device back (at most {self.remaining():.1f} s); "
                 "interrupt twice more to abandon it")

    def trace(self, phase: str) -> None:
        """Debug aid (ENCODER_CONFORMANCE_TRACE_STOP=1): seconds since the signal at each phase of the stop."""
        if self.at is not None and os.environ.get("ENCODER_CONFORMANCE_TRACE_STOP"):
            self.say(f"T+{time.monotonic() - self.at:.3f} {phase}")

    def _hard_exit(self) -> None:
        self.say(f"the run did not end within {HARD_LIMIT_S:.2f} s of the interrupt: exiting now")
        os._exit(self.exit_code or 130)

    def say(self, text: str) -> None:
        """A line on the real terminal, also while pytest captures the test's output."""
        with contextlib.suppress(OSError):
            os.write(self._stderr if self._stderr is not None else 2, (text + "\n").encode())
