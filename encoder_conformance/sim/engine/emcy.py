"""EMCY producer with the error register (1001h) and the pre-defined error field (1003h).

A behaviour: writing 0 to 1003h sub 0 clears the history (any other value is refused), power-on
starts with no history. An error is recorded in 1001h and 1003h whatever the NMT state; its EMCY
goes out in pre-operational and operational only (CiA 301 §7.3.2.2; in stopped too where the profile's
quirk says so), on the 1014h COB-ID while bit 31 is clear, no sooner than the 1015h inhibit time after
the previous one: an EMCY inside it waits (up to QUEUE_DEPTH of them, as CANopenNode's FIFO; more are
dropped) and goes out when the time is over. The faults that break it are the small classes at the bottom.
"""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Callable

from encoder_conformance.cia.cia301 import (
    COB_ID_FRAME_29_BIT,
    COB_ID_INVALID,
    EMCY_BASE,
    EMCY_COB_ID,
    EMCY_INHIBIT_TIME,
    ERROR_HISTORY,
    ERROR_REGISTER,
    ERROR_REGISTER_GENERIC,
    EmcyCode,
    SdoAbortCode,
)
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, ReloadEvent
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.object_store import ObjectStore
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler, JobHandle
from encoder_conformance.sim.engine.sdo_server import SdoAbort

QUEUE_DEPTH = 8


class EmcyProducer:
    """Builds EMCY frames (CiA 301 §7.2.7) and keeps 1001h/1003h up to date."""

    def __init__(
        self,
        store: ObjectStore,
        scheduler: DeadlineScheduler,
        send: Callable[[int, bytes], None],
        allowed: Callable[[], bool],
        node_id: Callable[[], int],
        without_generic_bit: bool = False,
        history_keeps_first: bool = False,
    ) -> None:
        self._store = store
        self._send = send
        self._allowed = allowed
        self._node_id = node_id
        self._without_generic_bit = without_generic_bit
        self._keeps_first = history_keeps_first
        self._scheduler = scheduler
        self._last_sent = -1e9
        self._waiting: list[bytes] = []  # EMCYs held back by the inhibit time
        self._flush: JobHandle | None = None
        self._lock = threading.RLock()  # the scheduler's thread sends the waiting EMCYs
        self._present: list[Callable[[], int]] = []  # 1001h bits of errors still present (NodeHooks.present_errors)

    def register(self, hooks: NodeHooks) -> None:
        hooks.commands.append(self._clear_history_command)
        self._present = hooks.present_errors
        hooks.reload.append(self._on_reload)
        hooks.halted.append(self._forget_waiting)

    def _clear_history_command(self, key: Key, value: object) -> bool:
        """1003h sub 0 = 0 clears the error history; other values are refused (CiA 301 §7.5.2, 1003h)."""
        if key != (ERROR_HISTORY, 0):
            return False
        if not self.clear_accepts(value):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        self.clear_history()
        return True

    def clear_accepts(self, value: object) -> bool:
        return value == 0

    def _on_reload(self, event: ReloadEvent) -> None:
        if event.name == "power_on":
            self.clear_history()

    def _cob_id(self) -> int | None:
        if self._store.has((EMCY_COB_ID, 0)):
            value = int(self._store.get((EMCY_COB_ID, 0)))
            if value & COB_ID_INVALID:
                return None
            return value & 0x1FFFFFFF if value & COB_ID_FRAME_29_BIT else value & 0x7FF
        return EMCY_BASE + self._node_id()

    def raise_error(self, code: int, register_bits: int, info: bytes = b"") -> None:
        """Record an error and send its EMCY (if the state and 1014h/1015h allow)."""
        register = self.register_value(register_bits)
        self._set_register(register)
        self._push_history(code)
        self._emit(code, register, info)

    def register_value(self, register_bits: int) -> int:
        """1001h for an error with ``register_bits``: bit 0 (generic) set with any other (CiA 301 §7.5.2, 1001h)."""
        return register_bits if self._without_generic_bit else register_bits | ERROR_REGISTER_GENERIC

    def clear(self) -> None:
        """The error went away: error register 0 and an EMCY 0000h (error reset), or, where others are still
        present (``NodeHooks.present_errors``), their bits in both, as CANopenNode's error reset carries them."""
        present = 0
        for bits in self._present:
            present |= bits()
        register = self.register_value(present) if present else 0
        self._set_register(register)
        self._emit(EmcyCode.ERROR_RESET, register, b"")

    def _set_register(self, value: int) -> None:
        if self._store.has((ERROR_REGISTER, 0)):
            self._store.set((ERROR_REGISTER, 0), value)

    def depth(self) -> int:
        return sum(1 for key in self._store.entries if key[0] == ERROR_HISTORY and key[1] > 0)

    def _push_history(self, code: int) -> None:
        depth = self.depth()
        if not depth:
            return
        count = int(self._store.get((ERROR_HISTORY, 0)))
        history = [int(self._store.get((ERROR_HISTORY, sub))) for sub in range(1, depth + 1)]
        for sub, value in enumerate(self.entered(history[:count], code, depth), start=1):
            self._store.set((ERROR_HISTORY, sub), value)
        self._store.set((ERROR_HISTORY, 0), self.counted(count, depth))

    def entered(self, history: list[int], code: int, depth: int) -> list[int]:
        """The history with ``code`` entered: at sub 1, the rest moved on (CiA 301 §7.5.2, 1003h: newest at
        sub 1), or after the older ones while there is room (quirk error_history_keeps_first)."""
        if self._keeps_first:
            return [*history, code][:depth]
        return [code, *history][:depth]

    def counted(self, count: int, depth: int) -> int:
        return min(depth, count + 1)

    def clear_history(self) -> None:
        for key in self._store.entries:
            if key[0] == ERROR_HISTORY:
                self._store.set(key, 0)

    def _emit(self, code: int, register: int, info: bytes) -> None:
        if self._cob_id() is None or not self.may_send():
            return
        frame = struct.pack("<HB", code, register) + info[:5].ljust(5, b"\x00")
        with self._lock:
            due = self._last_sent + self.inhibit_s()
            if not self._waiting and time.monotonic() >= due:
                self._transmit(frame)
                return
            if len(self._waiting) < QUEUE_DEPTH:
                self._waiting.append(frame)
            if self._flush is None:
                self._flush = self._scheduler.call_at(due, self._send_waiting)

    def _transmit(self, frame: bytes) -> None:
        cob_id = self._cob_id()
        if cob_id is None or not self.may_send():
            return
        self._last_sent = time.monotonic()
        self._send(cob_id, frame)

    def _send_waiting(self) -> None:
        """The inhibit time is over: the oldest waiting EMCY goes out, the next one an inhibit time later."""
        with self._lock:
            self._flush = None
            if not self._waiting:
                return
            self._transmit(self._waiting.pop(0))
            if self._waiting:
                self._flush = self._scheduler.call_at(self._last_sent + self.inhibit_s(), self._send_waiting)

    def _forget_waiting(self) -> None:
        with self._lock:
            self._waiting.clear()
            if self._flush is not None:
                self._flush.cancel()
                self._flush = None

    def may_send(self) -> bool:
        """The NMT state allows an EMCY (the node says which states do)."""
        return self._allowed()

    def inhibit_s(self) -> float:
        """1015h in seconds (100 us units; 0 or no 1015h: no inhibit time)."""
        if not self._store.has((EMCY_INHIBIT_TIME, 0)):
            return 0.0
        return int(self._store.get((EMCY_INHIBIT_TIME, 0))) / 10000


@breaks(EmcyProducer, "emcy_wrong_cob_id")
class EmcyOnWrongCobId(EmcyProducer):
    def _cob_id(self) -> int | None:
        cob_id = super()._cob_id()
        return None if cob_id is None else cob_id + 1


@breaks(EmcyProducer, "emcy_valid_bit_ignored")
class EmcyValidBitIgnored(EmcyProducer):
    def _cob_id(self) -> int | None:
        value = int(self._store.get((EMCY_COB_ID, 0))) if self._store.has((EMCY_COB_ID, 0)) else None
        return EMCY_BASE + self._node_id() if value is None else value & 0x7FF


@breaks(EmcyProducer, "emcy_without_generic_bit")
class EmcyWithoutGenericBit(EmcyProducer):
    def register_value(self, register_bits: int) -> int:
        return register_bits & ~ERROR_REGISTER_GENERIC or register_bits


@breaks(EmcyProducer, "emcy_inhibit_ignored")
class EmcyInhibitIgnored(EmcyProducer):  # every EMCY at once
    def inhibit_s(self) -> float:
        return 0.0


@breaks(EmcyProducer, "emcy_only_first")
class EmcyOnlyFirst(EmcyProducer):
    """After its first EMCY since the node was assembled or reset, the producer sends none (errors are still
    recorded in 1001h and 1003h)."""

    _sent_one = False

    def _transmit(self, frame: bytes) -> None:
        if not self._sent_one:
            self._sent_one = True
            super()._transmit(frame)


@breaks(EmcyProducer, "emcy_no_error_reset")
class EmcyNoErrorReset(EmcyProducer):
    def clear(self) -> None:
        self._set_register(0)


@breaks(EmcyProducer, "error_history_not_recorded")
class ErrorHistoryNotRecorded(EmcyProducer):
    def _push_history(self, code: int) -> None:
        pass


@breaks(EmcyProducer, "error_history_oldest_first")
class ErrorHistoryOldestFirst(EmcyProducer):
    def entered(self, history: list[int], code: int, depth: int) -> list[int]:
        return [*history, code][-depth:]


@breaks(EmcyProducer, "error_history_count_unlimited")
class ErrorHistoryCountUnlimited(EmcyProducer):
    def counted(self, count: int, depth: int) -> int:
        return min(0xFF, count + 1)


@breaks(EmcyProducer, "error_history_not_cleared")
class ErrorHistoryNotCleared(EmcyProducer):
    def clear_history(self) -> None:
        pass  # the write of 0 is confirmed, the history stays


@breaks(EmcyProducer, "error_history_any_value_accepted")
class ErrorHistoryAnyValueAccepted(EmcyProducer):
    def clear_accepts(self, value: object) -> bool:
        return True


@breaks(EmcyProducer, "emcy_in_stopped")
class EmcyInStoppedState(EmcyProducer):
    def may_send(self) -> bool:
        return True  # also in stopped

