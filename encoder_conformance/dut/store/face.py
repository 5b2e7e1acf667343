"""``dut.store``: making entries survive a reset the device's own way (1010h, a manufacturer store object, a store
that reboots), and the store commands a set of entries needs."""

from __future__ import annotations

from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.store.persist import StoreCommand, persist_entry, store_commands_for


class StoreFace:
    """What the device remembers, and how it is told to."""

    def __init__(self, dut: DeviceLink) -> None:
        self._dut = dut

    def persist(self, index: int, sub: int) -> str:
        """Store entry ``index``/``sub`` as its profile says it is stored; how (CannotPersist where it cannot)."""
        return persist_entry(self._dut, index, sub)

    def commands_for(self, keys: list[tuple[int, int]]) -> list[StoreCommand]:
        """The store commands that make the entries ``keys`` survive a reset, each once."""
        return store_commands_for(self._dut.profile, keys)
