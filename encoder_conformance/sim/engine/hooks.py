"""The registration points of a simulated node: what behaviours react to.

A behaviour registers for the objects and events it cares about; the node only runs the points in
order. Adding a behaviour (LSS, CAM, PDO mapping, ...) means writing it and registering it, not
editing the node.

Write path of an SDO download, after the access rules accepted it (``sim/engine/access.py``):
``gates`` (may refuse with an abort) -> ``commands`` (a command object consumes the write:
store/restore, clear error history) -> ``before_set`` -> the value is stored -> ``reactions``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import Key

Value = int | float | str | bytes  # float: a REAL32/REAL64 entry
#: refuses a write by raising SdoAbort
Gate = Callable[[Key, Value], None]
#: carries out a command written to an object; True when it consumed the write (nothing is stored)
Command = Callable[[Key, Value], bool]
#: reacts to a value about to be stored / just stored
Reaction = Callable[[Key, Value], None]


@dataclass(frozen=True)
class ReloadEvent:
    """What a (re)start reloaded: ``name`` is "power_on" (also a reboot), "nmt_81h" (reset node) or
    "nmt_82h" (reset communication); ``everything``: the application values too, not only 1000h-1FFFh."""

    name: str
    everything: bool


ReloadListener = Callable[[ReloadEvent], None]
StateListener = Callable[[NmtState], None]
#: a computed value of an entry (position, speed, ...) for a channel ("sdo"/"tpdo"), or None
ValueSource = Callable[[Key, str], Value | None]


@dataclass
class NodeHooks:
    """Registration points, run in registration order."""

    gates: list[Gate] = field(default_factory=list)
    commands: list[Command] = field(default_factory=list)
    before_set: list[Reaction] = field(default_factory=list)
    _reactions: list[tuple[frozenset[int] | None, Reaction]] = field(default_factory=list)
    reload: list[ReloadListener] = field(default_factory=list)
    state: list[StateListener] = field(default_factory=list)
    booted: list[Callable[[], None]] = field(default_factory=list)
    #: services stop: reset, reboot, power off (timers, transfers in progress)
    halted: list[Callable[[], None]] = field(default_factory=list)
    powered_off: list[Callable[[], None]] = field(default_factory=list)
    sources: list[ValueSource] = field(default_factory=list)
    #: SYNC frames, with their counter byte (None: a SYNC without counter, 1019h = 0)
    sync: list[Callable[[int | None], None]] = field(default_factory=list)
    #: SYNC frames, with their data length (the SYNC length check)
    sync_length: list[Callable[[int], None]] = field(default_factory=list)
    #: heartbeats of other nodes, with the producer's node-ID (the heartbeat consumer)
    heartbeat: list[Callable[[int], None]] = field(default_factory=list)
    remote_frame: list[Callable[[int], None]] = field(default_factory=list)
    #: LSS master frames (7E5h), whatever the NMT state
    lss: list[Callable[[bytes], None]] = field(default_factory=list)
    #: 1001h bits of errors still present: an error reset (another error going away) keeps them
    present_errors: list[Callable[[], int]] = field(default_factory=list)

    def on_written(self, reaction: Reaction, indices: Iterable[int] | None = None) -> None:
        """``reaction`` runs after a write to one of ``indices`` (None: any object) was stored."""
        self._reactions.append((None if indices is None else frozenset(indices), reaction))

    def written(self, key: Key, value: Value) -> None:
        for indices, reaction in list(self._reactions):
            if indices is None or key[0] in indices:
                reaction(key, value)

    def computed(self, key: Key, channel: str) -> Value | None:
        for source in self.sources:
            value = source(key, channel)
            if value is not None:
                return value
        return None

    def emit_reload(self, event: ReloadEvent) -> None:
        for listener in self.reload:
            listener(event)

    def emit_state(self, state: NmtState) -> None:
        for listener in self.state:
            listener(state)
