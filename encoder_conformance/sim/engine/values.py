"""What an entry reads as, through SDO or in a TPDO: computed by a behaviour, else the current value.

Behaviours that compute values (the encoder's position and speed, a quirk's read-back value)
register as ``sources`` in the node's hooks. Faults that falsify the identity objects are the
small classes at the bottom.
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.profile import datatypes
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.object_store import ObjectStore


class ObjectValues:
    """The read side of a node's object dictionary."""

    def __init__(self, store: ObjectStore, hooks: NodeHooks) -> None:
        self._store = store
        self._hooks = hooks

    def current(self, key: Key, channel: str = "sdo") -> Value:
        computed = self._hooks.computed(key, channel)
        if computed is not None:
            return computed
        return self.shown(key, self._store.get(key))

    def shown(self, key: Key, value: Value) -> Value:
        """A stored value as the device shows it (faults change identity values here)."""
        return value

    def encode(self, key: Key, channel: str = "sdo") -> bytes:
        value = self.current(key, channel)
        if isinstance(value, bytes):
            return value
        store = self._store
        if isinstance(value, str):
            return datatypes.string_bytes(store.entries[key].type, value)
        size = store.size(key)
        if isinstance(value, int) and size and not store.entries[key].type.startswith("REAL"):
            return (value & ((1 << (8 * size)) - 1)).to_bytes(size, "little")  # two's complement
        return store.variable(key).encode_raw(value)

    def mapped_bytes(self, index: int, sub: int, bits: int) -> bytes:
        """The bytes of a mapped entry in a TPDO (zeros for an entry the device lacks)."""
        key = (index, sub)
        if not self._store.has(key):
            return bytes(bits // 8)
        return self.encode(key, "tpdo").ljust(bits // 8, b"\x00")[: bits // 8]


def _identity_fault(name: str, key: Key, falsify: Callable[[int], int]) -> type[ObjectValues]:
    """A fault that shows the integer entry ``key`` falsified."""

    class IdentityFault(ObjectValues):
        def shown(self, shown_key: Key, value: Value) -> Value:
            value = super().shown(shown_key, value)
            return falsify(value) if shown_key == key and isinstance(value, int) else value

    IdentityFault.__name__ = IdentityFault.__qualname__ = "".join(part.title() for part in name.split("_"))
    return breaks(ObjectValues, name)(IdentityFault)


IDENTITY_FAULTS = [
    _identity_fault("wrong_vendor_id", (0x1018, 1), lambda v: (v + 1) & 0xFFFFFFFF),
    _identity_fault("wrong_product_code", (0x1018, 2), lambda v: (v + 1) & 0xFFFFFFFF),
    _identity_fault("wrong_revision", (0x1018, 3), lambda v: 0xFFFFFFFF),
    _identity_fault("wrong_identity_size", (0x1018, 0), lambda v: v + 1),
    _identity_fault("serial_mismatch", (0x1018, 4), lambda v: (v ^ 0x1) & 0xFFFFFFFF),
    _identity_fault("serial_unset", (0x1018, 4), lambda v: 0xFFFFFFFF),
    _identity_fault("wrong_device_type", (0x1000, 0), lambda v: (v & 0xFFFF0000) | ((v + 1) & 0xFFFF)),
]


@breaks(ObjectValues, "wrong_device_name")
class WrongDeviceName(ObjectValues):
    def shown(self, key: Key, value: Value) -> Value:
        value = super().shown(key, value)
        return f"X{value}" if key == (0x1008, 0) and isinstance(value, str) else value  # 1008h: a VISIBLE_STRING


@breaks(ObjectValues, "mapped_values_change_every_read")
class CountsAtEverySync(ObjectValues):
    """A hold fault: an SDO read of a PDO-mappable integer entry shows its value plus the SYNCs since the last
    (re)start: the mapped objects change between a read before a SYNC and a read after it."""

    def __init__(self, store: ObjectStore, hooks: NodeHooks) -> None:
        super().__init__(store, hooks)
        self._syncs = 0
        hooks.sync.append(self._count)
        hooks.reload.append(lambda event: self._restart())

    def _count(self, counter: int | None) -> None:
        self._syncs += 1

    def _restart(self) -> None:
        self._syncs = 0

    def current(self, key: Key, channel: str = "sdo") -> Value:
        value = super().current(key, channel)
        entry = self._store.entries.get(key)
        if channel != "sdo" or not isinstance(value, int) or entry is None or not entry.pdo_mappable:
            return value
        return value + self._syncs
