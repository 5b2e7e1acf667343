"""A point in time a device's restore must not pass (``custody.give_back`` has a bound in seconds)."""

from __future__ import annotations

import time


class Deadline:
    """A point in time the restore must not pass."""

    def __init__(self, seconds: float) -> None:
        self.end = time.monotonic() + seconds
        self.seconds = seconds

    def expired(self) -> bool:
        return time.monotonic() >= self.end

    def check(self, doing: str) -> None:
        """Raise TimeoutError naming what was next (``doing``) once the time is up."""
        if self.expired():
            raise TimeoutError(f"the restore ran out of time ({self.seconds:.1f} s) before {doing}")
