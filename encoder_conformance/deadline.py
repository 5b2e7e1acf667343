"""A point in time a wait must not pass: every deadline of the tester, the twin's launcher and the tools (a
restore's bound, an answer window, a process that must have ended)."""

from __future__ import annotations

import time


class Deadline:
    """A point on the monotonic clock, ``seconds`` after now (or after ``since``, an earlier ``time.monotonic()``).
    A loop stops once it ``expired()``, hands ``remaining()`` to a blocking wait, or calls ``check(doing)``, which
    raises TimeoutError naming ``what`` ran out of time."""

    def __init__(self, seconds: float, what: str = "the wait", since: float | None = None) -> None:
        self.seconds = seconds
        self.what = what
        self.end = (time.monotonic() if since is None else since) + seconds

    def remaining(self) -> float:
        """Seconds left (0 once expired): a time-out that ends with the deadline."""
        return max(0.0, self.end - time.monotonic())

    def expired(self) -> bool:
        return time.monotonic() >= self.end

    def check(self, doing: str) -> None:
        """Raise TimeoutError naming what was next (``doing``) once the time is up."""
        if self.expired():
            raise TimeoutError(f"{self.what} ran out of time ({self.seconds:.1f} s) before {doing}")
