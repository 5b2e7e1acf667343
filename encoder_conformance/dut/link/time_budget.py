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

CATEGORIES = ("sdo", "send", "answer", "silence", "periodic", "boot-up", "execution", "generation")


class Booking:
    """One wait being measured, as a context manager; its category may change once its outcome is known (a
    timed-out answer wait is a silence). A class, not a generator: it wraps every SDO transfer and frame sent, and
    ``contextlib.contextmanager``'s generator cost several times as much per wait."""

    __slots__ = ("_booked", "_budget", "_cpu", "_outer", "_start", "category")

    def __init__(self, budget: TimeBudget, category: str) -> None:
        self.category = category
        self._budget = budget
        self._booked = False  # a wait of the booking thread (another thread's is not booked)
        self._outer = False  # the outermost booking of the booking thread: the one that counts
        self._start = self._cpu = 0.0

    def __enter__(self) -> Booking:
        budget = self._budget
        if threading.current_thread() is budget.thread:
            self._booked, self._outer = True, budget.depth == 0
            budget.depth += 1
            if self._outer:
                self._start, self._cpu = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc: object) -> None:
        if not self._booked:
            return
        budget = self._budget
        budget.depth -= 1
        if self._outer:
            budget.add(self.category, time.perf_counter() - self._start, time.process_time() - self._cpu)


class TimeBudget:
    """Seconds owed per category, summed over the process (one run per process)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._totals = dict.fromkeys(CATEGORIES, 0.0)
        self._cpu = dict.fromkeys(CATEGORIES, 0.0)  # this process's CPU seconds inside each category's waits
        self.depth = 0  # bookings open in the booking thread (only that thread changes it)
        self.thread: threading.Thread = threading.main_thread()  # the thread whose waits are booked

    def booking(self, category: str) -> Booking:
        """``with budget.booking("answer") as booking:`` books the wait's seconds to ``booking.category``."""
        return Booking(self, category)

    def add(self, category: str, seconds: float, cpu: float) -> None:
        with self._lock:
            self._totals[category] = self._totals.get(category, 0.0) + seconds
            self._cpu[category] = self._cpu.get(category, 0.0) + cpu

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
