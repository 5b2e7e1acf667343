"""The cyclic timer (CiA 406 6200h) and TPDO1's event timer (1800h sub 5) where a manual leaves their relation
open (quirk effect ``cyclic_timer_relation_unstated``; the WDGA manual, T 6.3 and T 6.6).

The default twin keeps two values: a write to one leaves the other as it is. Its variant plays one value
behind both entries, as CiA 406 v3.0 ties them: a write to either sets both (both in ms). Each entry still
loads its own stored value or default at a reset, so a device fresh from the factory reads 6200h = 0001h
and 1800h sub 5 = 0000h, a state no sequence of writes can bring back; a reset node does.
"""

from __future__ import annotations

from encoder_conformance.profile.quirk_effects import CyclicTimerRelationUnstated
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.object_store import ObjectStore


class CyclicTimerLink:
    """What a write to one of the two timers does to the other: nothing (the default twin)."""

    def __init__(self, params: CyclicTimerRelationUnstated, store: ObjectStore) -> None:
        cyclic, event = params.cyclic_timer, params.event_timer
        self._partner: dict[Key, Key] = {(cyclic.index, cyclic.sub): (event.index, event.sub),
                                         (event.index, event.sub): (cyclic.index, cyclic.sub)}
        self._store = store
        self._hooks: NodeHooks | None = None

    def register(self, hooks: NodeHooks) -> None:
        self._hooks = hooks
        hooks.on_written(self.after_write, {key[0] for key in self._partner})

    def one_value(self) -> bool:
        """Whether both entries are one value."""
        return False

    def after_write(self, key: Key, value: Value) -> None:
        """A timer was written: where both are one value, the other takes it too (and its reactions run)."""
        other = self._partner.get(key)
        if other is None or not self.one_value() or not self._store.has(other) or self._store.get(other) == value:
            return
        self._store.set(other, value)
        assert self._hooks is not None  # registered before any write
        self._hooks.written(other, value)  # the TPDO engine reloads its event timer


@breaks(CyclicTimerLink, "cyclic_timer_aliases_event_timer")
class OneTimerValue(CyclicTimerLink):
    """A variant, not a fault: 6200h and 1800h sub 5 are one value; writing either sets both."""

    def one_value(self) -> bool:
        return True
