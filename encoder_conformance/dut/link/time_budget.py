"""What a run owes the device, measured: every wait the tester makes for it, booked to what it waits for.

The categories: ``sdo`` (an SDO transfer through canopen, request to last answer), ``send`` (a frame handed to the
bus interface outside a transfer: the adapter's time to take it, bus traffic as an SDO transfer's own frames are),
``answer`` (a frame waited for that came: the device's answer time), ``silence`` (an observation window, or a wait
that ended without the frame: owed in full), ``periodic`` (several periodic frames captured), ``boot-up`` (reset
or power-on to the boot-up message), ``execution`` (a manual's execution time waited out) and ``generation`` (a
fuzzing budget the user gave, ``--fuzz-budget``: owed by choice). What a run takes beyond their sum is the
tester's own work: collection, evidence, reports, the plugin.

Only the thread that runs the tests books (a background capture's waits overlap the test's own), and nested
waits count once, under the outermost booking (a boot-up wait made of frame waits is a boot-up).

Beside each category's seconds, the tester process's own CPU seconds inside them (all its threads: the SDO
client, the receive thread, the frame log): still owed by the category's meaning (an SDO transfer is request to
last answer), but they tell how much of an owed figure was the tester's own work rather than the device's
(measured on the WDGA twin: about half of ``sdo``, little of the windows).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

CATEGORIES = ("sdo", "send", "answer", "silence", "periodic", "boot-up", "execution", "generation")


@dataclass
class Booking:
    """One wait being measured; its category may change once its outcome is known (a timed-out answer wait
    is a silence)."""

    category: str


class TimeBudget:
    """Seconds owed per category, summed over the process (one run per process)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._totals = dict.fromkeys(CATEGORIES, 0.0)
        self._cpu = dict.fromkeys(CATEGORIES, 0.0)  # this process's CPU seconds inside each category's waits
        self._depth = threading.local()
        self.thread: threading.Thread = threading.main_thread()  # the thread whose waits are booked

    @contextmanager
    def booking(self, category: str) -> Iterator[Booking]:
        booking = Booking(category)
        if threading.current_thread() is not self.thread:
            yield booking
            return
        depth = getattr(self._depth, "value", 0)
        self._depth.value = depth + 1
        start, cpu = time.perf_counter(), time.process_time()
        try:
            yield booking
        finally:
            self._depth.value = depth
            if depth == 0:
                elapsed, used = time.perf_counter() - start, time.process_time() - cpu
                with self._lock:
                    self._totals[booking.category] = self._totals.get(booking.category, 0.0) + elapsed
                    self._cpu[booking.category] = self._cpu.get(booking.category, 0.0) + used

    def snapshot(self) -> dict[str, float]:
        with self._lock:
            return dict(self._totals)

    def cpu_snapshot(self) -> dict[str, float]:
        """This process's CPU seconds inside each category's waits so far (see the module's docstring)."""
        with self._lock:
            return dict(self._cpu)


#: the process's ledger (a run is one process; the suites' waits all go through the DUT layer)
BUDGET = TimeBudget()


def difference(after: dict[str, float], before: dict[str, float]) -> dict[str, float]:
    """Seconds booked between two snapshots, per category (categories with none left out)."""
    return {key: round(value - before.get(key, 0.0), 6) for key, value in after.items()
            if value - before.get(key, 0.0) > 0}
