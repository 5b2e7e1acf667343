"""Heartbeat producer (CiA 301 §7.2.8.3.2.2): one frame with the NMT state every 1017h ms.

Faults that break it are the small classes at the bottom, each overriding one decision.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from encoder_conformance.cia.cia301 import HEARTBEAT_BASE
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler, JobHandle

HEARTBEAT_OBJECT = 0x1017


class HeartbeatProducer:
    """Sends the heartbeat on the scheduler; restarts when 1017h is written or the node boots."""

    def __init__(
        self,
        scheduler: DeadlineScheduler,
        send: Callable[[int, bytes], None],
        read_int: Callable[[int, int], int | None],
        state: Callable[[], NmtState | None],
        node_id: Callable[[], int],
        enabled: bool,
    ) -> None:
        self._scheduler = scheduler
        self._send = send
        self._read_int = read_int
        self._state = state
        self._node_id = node_id
        self._enabled = enabled
        self._job: JobHandle | None = None

    def register(self, hooks: NodeHooks) -> None:
        hooks.booted.append(self.restart)
        hooks.on_written(self.on_write, [HEARTBEAT_OBJECT])

    def on_write(self, key: Key, value: Value) -> None:
        self.restart()

    def period_s(self) -> float:
        return (self._read_int(HEARTBEAT_OBJECT, 0) or 0) / 1000

    def stop(self) -> None:
        if self._job is not None:
            self._job.cancel()
            self._job = None

    def restart(self) -> None:
        self.stop()
        period = self.period_s()
        if period <= 0 or not self._enabled:
            return
        self._schedule(time.monotonic(), period)

    def _schedule(self, start: float, period: float) -> None:
        self._job = self._scheduler.call_at(start + period, self.send, period)

    def payload(self, state: NmtState) -> bytes:
        return bytes([int(state)])

    def send(self) -> None:
        state = self._state()
        if state is None or state is NmtState.INITIALISING:
            return
        self._send(HEARTBEAT_BASE + self._node_id(), self.payload(state))


@breaks(HeartbeatProducer, "heartbeat_slow_20pct")
class SlowHeartbeat(HeartbeatProducer):
    def period_s(self) -> float:
        return super().period_s() * 1.2


@breaks(HeartbeatProducer, "heartbeat_jitter")
class JitteryHeartbeat(HeartbeatProducer):
    """Every 4th heartbeat comes 30 % of the period late (the schedule itself stays)."""

    def _schedule(self, start: float, period: float) -> None:
        self._count = 0
        self._job = self._scheduler.call_at(start + period, lambda: self._jittered(start, period))

    def _jittered(self, start: float, period: float) -> None:
        self.send()
        self._count += 1
        k = self._count + 1
        due = start + k * period + (0.3 * period if k % 4 == 0 else 0.0)
        self._job = self._scheduler.call_at(due, lambda: self._jittered(start, period))


@breaks(HeartbeatProducer, "wrong_heartbeat_state")
class HeartbeatClaimsOperational(HeartbeatProducer):
    def payload(self, state: NmtState) -> bytes:
        shown = NmtState.OPERATIONAL if state is NmtState.PRE_OPERATIONAL else state
        return super().payload(shown)


@breaks(HeartbeatProducer, "heartbeat_wrong_dlc")
class LongHeartbeat(HeartbeatProducer):
    def payload(self, state: NmtState) -> bytes:
        return super().payload(state) + b"\x00"


@breaks(HeartbeatProducer, "heartbeat_ignores_zero")
class HeartbeatIgnoresZero(HeartbeatProducer):
    def on_write(self, key: Key, value: Value) -> None:
        if value != 0:
            super().on_write(key, value)


@breaks(HeartbeatProducer, "heartbeat_state_stale")
class HeartbeatStateStale(HeartbeatProducer):
    """The state byte is the state at the producer's (re)start (boot-up, 1017h write), not the present one."""

    _shown: NmtState | None = None

    def restart(self) -> None:
        self._shown = self._state()
        super().restart()

    def payload(self, state: NmtState) -> bytes:
        return super().payload(self._shown or state)
