"""A Ctrl-C during start-up ends the run even where the interpreter dropped its KeyboardInterrupt (seen in CI:
SIGINT 1.0 s into a loaded run, the run went on to the end with exit code 0)."""

from __future__ import annotations

import signal

import pytest

from encoder_conformance.plugin import interrupt
from encoder_conformance.plugin.interrupt import InterruptGuard


class NoWatchdog:
    """The guard's watchdog would end this test process 2 s later."""

    def __init__(self, *args, **kwargs) -> None:
        self.daemon = True

    def start(self) -> None:
        pass


def test_guard_stops_the_run_for_a_signal_that_came_before_it(monkeypatch):
    monkeypatch.setattr(interrupt, "EARLY_SIGNALS", [signal.SIGINT])
    monkeypatch.setattr(interrupt.threading, "Timer", NoWatchdog)
    stopped: list[str] = []
    guard = InterruptGuard(on_stop=stopped.append)
    try:
        with pytest.raises(KeyboardInterrupt):
            guard.install()
        assert guard.exit_code == 130
        assert stopped == ["interrupted (SIGINT)"]
    finally:
        guard.uninstall()


def test_no_early_signal_no_stop(monkeypatch):
    monkeypatch.setattr(interrupt, "EARLY_SIGNALS", [])
    guard = InterruptGuard(on_stop=lambda reason: None)
    try:
        guard.install()
        assert guard.exit_code is None
    finally:
        guard.uninstall()
