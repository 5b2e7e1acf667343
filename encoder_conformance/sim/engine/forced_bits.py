"""Bits a device forces to 1 in a stored value at initialisation (quirk effect ``bits_forced_at_init``).

Example (SIKO WV58M/WH58M, M §5.2.15): 1801h sub 1 is stored in EEPROM, yet bit 31 (PDO2 not
valid) is set again at every power-on and NMT reset node / reset communication. Only the current
value changes; the stored one stays as written.
"""

from __future__ import annotations

from encoder_conformance.profile.quirk_effects import BitsForcedAtInit
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, ReloadEvent
from encoder_conformance.sim.engine.object_store import ObjectStore


def force_bits(params: BitsForcedAtInit | None, store: ObjectStore, event: str) -> None:
    """Set ``forced_bits`` in the current value of index/subindex if ``event`` is listed in ``at``."""
    if params is None or event not in params.at:
        return
    key = params.key
    value = store.get(key) if store.has(key) else None
    if isinstance(value, int):
        store.set(key, value | params.forced_bits)


class ForcedBits:
    """A behaviour: applies the quirk at every initialisation event."""

    def __init__(self, params: BitsForcedAtInit, store: ObjectStore) -> None:
        self._params = params
        self._store = store

    def register(self, hooks: NodeHooks) -> None:
        hooks.reload.append(self.on_reload)

    def on_reload(self, event: ReloadEvent) -> None:
        force_bits(self._params, self._store, event.name)


@breaks(ForcedBits, "forced_bits_not_applied")
class ForcedBitsNotApplied(ForcedBits):
    def on_reload(self, event: ReloadEvent) -> None:
        return  # the value keeps its stored bits
