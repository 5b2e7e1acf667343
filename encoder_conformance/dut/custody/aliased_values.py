"""Entries that alias: a write to one changes another (one value behind two objects; the WDGA's 6200h and
1800h sub 5 in one reading of its manual, open reading ``cyclic-timer-vs-event-timer``).

Nothing on the bus says so before a write; the custody finds them by reading back. An entry that still differs
from its target after the write-back, and each written entry that now holds the same value, are written one at
a time and read back: "writing A changed B" is an edge. They are then written again in an order where an entry
comes before those its write changes. Two entries that change each other and want different values (a device
fresh from the factory: 6200h = 0001h, 1800h sub 5 = 0000h) have no such order: the caller may give them back
by NMT reset node where they were the stored values (CiA 301 §7.2.8.3.2.2: reset node loads the stored values),
and stores them one at a time where each has a store command of its own (1010h sub 2 and sub 3 on the WDGA).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.dut.custody.snapshot import Snapshot
from encoder_conformance.profile.quirk_effects import CyclicTimerRelationUnstated
from encoder_conformance.profile.schema import DeviceProfile

Key = tuple[int, int]
Values = dict[Key, bytes | None]


def entries_that_may_alias(profile: DeviceProfile) -> frozenset[Key]:
    """Entries the profile's manual lists beside another without saying whether they are one value: a run that
    promises to write nothing it cannot put back (``accept``) leaves them alone."""
    quirk = profile.params_of(CyclicTimerRelationUnstated)
    if quirk is None:
        return frozenset()
    return frozenset((key.index, key.sub) for key in (quirk.cyclic_timer, quirk.event_timer))


def label(key: Key) -> str:
    return f"{key[0]:04X}h.{key[1]:02X}"


@dataclass
class AliasOutcome:
    """What the read-back found: the edges, and the entries no order of writes gives back."""

    edges: set[tuple[Key, Key]] = field(default_factory=set)  #: (written, changed by that write)
    written: list[str] = field(default_factory=list)  #: the writes made, as the record lists them
    conflicting: list[Key] = field(default_factory=list)  #: no order gives them back (empty: none, or solved)

    def describe(self) -> str:
        """One line on the entries that change each other."""
        pairs = sorted({tuple(sorted(edge)) for edge in self.edges})
        return "; ".join(f"writing {label(a)} or {label(b)} changes the other" if (b, a) in self.edges
                         else f"writing {label(a)} changes {label(b)}" for a, b in pairs)


def write_order(group: list[Key], edges: set[tuple[Key, Key]], targets: dict[Key, bytes]) -> list[Key] | None:
    """``group`` in an order where an entry comes before every entry its write changes to another value than that
    one's target; None where the edges form a cycle (no order can)."""
    after = {key: {b for a, b in edges if a == key and b in targets and targets[b] != targets[key]} for key in group}
    order: list[Key] = []
    left = set(group)
    while left:
        ready = sorted(k for k in left if not any(k in after[other] for other in left if other != k))
        if not ready:
            return None
        order.append(ready[0])
        left.remove(ready[0])
    return order


def no_reset_gives_back(snapshot: Snapshot | None, outcome: AliasOutcome) -> str | None:
    """Why NMT reset node cannot be shown to give the conflicting entries back (None: it can: each was found
    holding its stored value)."""
    entries = [snapshot.entry(key) if snapshot else None for key in outcome.conflicting]
    names = ", ".join(label(key) for key in outcome.conflicting)
    head = f"{outcome.describe()}: no order of writes gives back {names} as found"
    if any(e is None or e.stored is None for e in entries):
        return (f"{head}, and the run did not read what the device has stored (an acceptance sends no reset), so a "
                "reset node cannot be shown to give them back; where they were the stored values, NMT reset node does")
    if any(e is not None and e.found is not None and e.found != e.stored for e in entries):
        return f"{head}, and they were not the stored values when the run began, so a reset node would not either"
    return None


class AliasRepair:
    """Finds aliased entries among those a write-back left wrong, and writes them back in an order that works."""

    def __init__(self, read: Callable[[list[Key]], Values], write: Callable[[Key, bytes], None]) -> None:
        self._read = read
        self._write = write

    def repair(self, targets: dict[Key, bytes], now: Values, written: list[Key]) -> AliasOutcome:
        """``now``: the values read after the write-back of ``written``; the outcome's ``conflicting`` entries
        are those still wrong that change each other (no order of writes gives them back)."""
        outcome = AliasOutcome()
        failing = [k for k, v in targets.items() if now.get(k) != v]
        group = sorted({*failing, *(w for w in written for f in failing
                                    if w != f and w in targets and now.get(w) == now.get(f))})
        if len(group) < 2:
            return outcome
        state = {k: now.get(k) for k in group}
        # one write at a time, the wrong entries first: what a later write changes back then shows
        for key in sorted(group, key=lambda k: k not in failing):
            if not self._write_one(key, targets[key], outcome):
                continue
            seen = self._read(group)
            outcome.edges |= {(key, other) for other in group if other != key and seen[other] != state[other]}
            state = seen
        order = write_order(group, outcome.edges, targets)
        if order is None:  # the entries of a cycle, and whatever their writes change
            outcome.conflicting = sorted({k for a, b in outcome.edges if targets[a] != targets[b] for k in (a, b)})
            return outcome
        for key in order:
            self._write_one(key, targets[key], outcome)
        state = self._read(group)
        outcome.conflicting = [k for k in group if state[k] != targets[k] and any(k in e for e in outcome.edges)]
        return outcome

    def _write_one(self, key: Key, value: bytes, outcome: AliasOutcome) -> bool:
        try:
            self._write(key, value)
        except SdoAbortedError:
            return False
        outcome.written.append(f"{label(key)} = {value.hex(' ').upper()} (aliased entries)")
        return True
