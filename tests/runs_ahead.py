"""The slow modules' suite sessions, started in the background when the self-test session starts (shared helper).

Each slow module (a matrix, the twins' full runs) declares its sessions in a module-level function
``sessions_ahead(runs: RunsAhead) -> {key: make}``; a module whose slow part starts no suite session (a wheel's
install) declares it as ``work_ahead``, started at once in a pool of its own. At session start the conftest starts
every declared session of the selected modules in a background pool, in collection order (the order their fixtures
will ask); they take
only the session slots the foreground leaves free (encoder_conformance/runs/session_slots.py). A module's fixture
asks for the same keys (``runs.results``) and gets each result made once: waited for where it is running, made
there (in the foreground, before any background session) where it has not started. Before, each slow module ran
its sessions in a pool of its own when its turn came, and the machine idled through the other modules and
through each pool's last runs.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Hashable, Mapping
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from encoder_conformance.runs.session_slots import SESSION_SLOTS
from tests.suite_session import PARALLEL_RUNS, FaultRuns, FullRuns, _Once

#: threads for the jobs that start no suite session (``start(..., side=True)``)
SIDE_WORKERS = 2


class RunsAhead(_Once[Hashable, Any]):
    """Results of the slow modules' sessions, made once per self-test session, most of them ahead of time."""

    def __init__(self, mktemp: Callable[[str], Path], full_runs: FullRuns, fault_runs: FaultRuns):
        super().__init__(mktemp)
        self.mktemp = mktemp
        self.full_runs = full_runs
        self.fault_runs = fault_runs
        self._pool: ThreadPoolExecutor | None = None
        self._side_pool: ThreadPoolExecutor | None = None
        self._made = {"background": 0, "foreground": 0}
        self._counting = threading.Lock()
        self._waited_s = 0.0

    def _once(self, key: Hashable, make: Callable[[], Any]) -> Any:
        def counted() -> Any:
            result = make()
            with self._counting:
                self._made["background" if threading.current_thread().name.startswith("ahead") else "foreground"] += 1
            return result

        return super()._once(key, counted)

    def start(self, jobs: Mapping[Hashable, Callable[[], Any]], side: bool = False) -> None:
        """Makes each job in the background (errors are left for the foreground's own call to raise). ``side``:
        jobs that start no suite session (a wheel's build and install), in a pool of their own that starts them at
        once, not behind the sessions waiting for a slot."""
        if side:
            if self._side_pool is None:
                self._side_pool = ThreadPoolExecutor(max_workers=SIDE_WORKERS, thread_name_prefix="ahead-side",
                                                     initializer=SESSION_SLOTS.mark_background)
            pool = self._side_pool
        else:
            if self._pool is None:
                self._pool = ThreadPoolExecutor(max_workers=PARALLEL_RUNS, thread_name_prefix="ahead",
                                                initializer=SESSION_SLOTS.mark_background)
            pool = self._pool
        for key, make in jobs.items():
            pool.submit(self._once, key, make)

    def results(self, jobs: Mapping[Hashable, Callable[[], Any]], workers: int = PARALLEL_RUNS) -> dict[Hashable, Any]:
        """Each job's result, in the order given: those not started yet are made here, ``workers`` at a time."""
        start = time.monotonic()
        with ThreadPoolExecutor(max_workers=workers) as pool:
            results = dict(zip(jobs, pool.map(lambda job: self._once(*job), jobs.items()), strict=True))
        self._waited_s += time.monotonic() - start
        return results

    def one(self, key: Hashable, make: Callable[[], Any]) -> Any:
        """One job's result, made once: waited for where it is being made, made here where it has not started (a
        background job that needs another's result asks this way)."""
        return self._once(key, make)

    def summary_worth_printing(self) -> bool:
        return any(self._made.values())

    def summary(self) -> str:
        """One line: how many results were made ahead, how many by their module, how long the modules waited."""
        return (f"slow modules' sessions: {self._made['background']} made ahead in the background, "
                f"{self._made['foreground']} by their module; the modules waited {self._waited_s:.0f} s for them")

    def close(self) -> None:
        """Drops the jobs not started; waits for the running ones (a session is never left behind)."""
        for pool in (self._pool, self._side_pool):
            if pool is not None:
                pool.shutdown(wait=True, cancel_futures=True)
