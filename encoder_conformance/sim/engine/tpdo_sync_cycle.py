"""A TPDO engine that takes SYNCs in a processing cycle (a conformant variant of ``tpdo.TpdoEngine``).

CiA 301 v4.2.0 §7.2.5 gives no shortest time between two SYNCs that a consumer must tell apart. A device that
handles received frames in a cycle of its main loop (CANopenNode's Linux demo: 1 ms, one flag per received SYNC)
counts the SYNCs that arrive before its next cycle as one, and answers a SYNC at that cycle. A tester owes such a
device the time it takes to process each SYNC: the TPDO that SYNC brings, or the profile's timing.pdo_response_max_ms.
"""

from __future__ import annotations

from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.scheduler import JobHandle
from encoder_conformance.sim.engine.tpdo import TpdoEngine

CYCLE_S = 0.001  # CANopenNode's mainline period on Linux


@breaks(TpdoEngine, "sync_processing_cycle")
class SyncProcessingCycle(TpdoEngine):
    """A variant, not a fault: a SYNC is taken at the next cycle; more SYNCs before it are merged with it."""

    _pending: JobHandle | None = None

    def on_sync(self, counter: int | None = None) -> None:
        if self._pending is not None:
            return  # the flag is already set: this SYNC is not counted on its own

        def take() -> None:
            self._pending = None
            super(SyncProcessingCycle, self).on_sync(counter)

        self._pending = self._scheduler.call_later(CYCLE_S, take)
