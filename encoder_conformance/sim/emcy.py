"""EMCY producer with the error register (1001h) and the pre-defined error field (1003h).

A behaviour: writing 0 to 1003h sub 0 clears the history (any other value is refused), power-on
starts with no history. The fault that breaks it is the small class at the bottom.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable

from ..cia301 import SdoAbortCode
from .faults import breaks
from .hooks import NodeHooks, ReloadEvent
from .nvm import Key
from .object_store import ObjectStore
from .sdo_server import SdoAbort

GENERIC_ERROR_BIT = 0x01


class EmcyProducer:
    """Builds EMCY frames (CiA 301 §7.2.7) and keeps 1001h/1003h up to date."""

    def __init__(
        self,
        store: ObjectStore,
        send: Callable[[int, bytes], None],
        allowed: Callable[[], bool],
        node_id: Callable[[], int],
        without_generic_bit: bool = False,
    ) -> None:
        self._store = store
        self._send = send
        self._allowed = allowed
        self._node_id = node_id
        self._without_generic_bit = without_generic_bit
        self._last_sent = -1e9

    def register(self, hooks: NodeHooks) -> None:
        hooks.commands.append(self._clear_history_command)
        hooks.reload.append(self._on_reload)

    def _clear_history_command(self, key: Key, value: object) -> bool:
        """1003h sub 0 = 0 clears the error history; other values are refused (CiA 301 §7.5.2.5)."""
        if key != (0x1003, 0):
            return False
        if value != 0:
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        self.clear_history()
        return True

    def _on_reload(self, event: ReloadEvent) -> None:
        if event.name == "power_on":
            self.clear_history()

    def _cob_id(self) -> int | None:
        if self._store.has((0x1014, 0)):
            value = int(self._store.get((0x1014, 0)))
            if value & 0x80000000:
                return None
            return value & 0x1FFFFFFF if value & 0x20000000 else value & 0x7FF
        return 0x80 + self._node_id()

    def raise_error(self, code: int, register_bits: int, info: bytes = b"") -> None:
        """Record an error and send its EMCY (if the state and 1014h/1015h allow)."""
        register = register_bits if self._without_generic_bit else register_bits | GENERIC_ERROR_BIT
        self._set_register(register)
        self._push_history(code)
        self._emit(code, register, info)

    def clear(self) -> None:
        """All errors gone: error register 0 and an EMCY 0000h (error reset)."""
        self._set_register(0)
        self._emit(0x0000, 0, b"")

    def _set_register(self, value: int) -> None:
        if self._store.has((0x1001, 0)):
            self._store.set((0x1001, 0), value)

    def _push_history(self, code: int) -> None:
        depth = sum(1 for key in self._store.entries if key[0] == 0x1003 and key[1] > 0)
        if not depth:
            return
        history = [int(self._store.get((0x1003, sub))) for sub in range(1, depth + 1)]
        history = [code, *history[:-1]]  # newest at sub 1 (CiA 301 §7.5.2.3)
        for sub, value in enumerate(history, start=1):
            self._store.set((0x1003, sub), value)
        count = int(self._store.get((0x1003, 0)))
        self._store.set((0x1003, 0), min(depth, count + 1))

    def clear_history(self) -> None:
        for key in self._store.entries:
            if key[0] == 0x1003:
                self._store.set(key, 0)

    def _emit(self, code: int, register: int, info: bytes) -> None:
        cob_id = self._cob_id()
        if cob_id is None or not self._allowed():
            return
        inhibit_s = int(self._store.get((0x1015, 0))) / 10000 if self._store.has((0x1015, 0)) else 0.0
        now = time.monotonic()
        if inhibit_s and now - self._last_sent < inhibit_s:
            return
        self._last_sent = now
        self._send(cob_id, struct.pack("<HB", code, register) + info[:5].ljust(5, b"\x00"))


@breaks(EmcyProducer, "emcy_wrong_cob_id")
class EmcyOnWrongCobId(EmcyProducer):
    def _cob_id(self) -> int | None:
        cob_id = super()._cob_id()
        return None if cob_id is None else cob_id + 1
