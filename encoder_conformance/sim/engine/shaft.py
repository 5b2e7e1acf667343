"""A simulated shaft: angle in revolutions, turned by the control API or a constant speed."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable


class Shaft:
    """Continuous angle (revolutions, may be negative) moving at ``speed`` rev/s."""

    def __init__(self, turns: float = 0.0) -> None:
        self._lock = threading.Lock()
        self._turns = turns
        self._speed = 0.0
        self._since = time.monotonic()
        #: called after every move the control API makes (the CAM history follows the shaft)
        self.listeners: list[Callable[[], None]] = []

    def _moved(self) -> None:
        for listener in self.listeners:
            listener()

    def turns(self) -> float:
        with self._lock:
            return self._turns + self._speed * (time.monotonic() - self._since)

    @property
    def speed(self) -> float:
        return self._speed

    def _settle(self) -> None:
        now = time.monotonic()
        self._turns += self._speed * (now - self._since)
        self._since = now

    def turn_by(self, revolutions: float) -> None:
        with self._lock:
            self._settle()
            self._turns += revolutions
        self._moved()

    def set_turns(self, revolutions: float) -> None:
        with self._lock:
            self._settle()
            self._turns = revolutions
        self._moved()

    def set_speed(self, revolutions_per_second: float) -> None:
        with self._lock:
            self._settle()
            self._speed = revolutions_per_second
