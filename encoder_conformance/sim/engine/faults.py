"""How a named fault breaks a simulator behaviour: as a small mixin class next to that behaviour.

A behaviour (heartbeat producer, SDO access rules, store commands, TPDO engine, ...) exposes the
decisions a fault may change as methods. A fault is a class that overrides one of them, declared
next to the behaviour with ``@breaks(Behaviour, "fault_name")``. When the node assembles its
behaviours, ``assemble(Behaviour, faults)`` returns the behaviour class with the active faults'
mixins in front, so the behaviour itself never asks which faults are active.

The names, descriptions and target suites of the faults live in ``fault_catalogue`` (data the
plugin may import without the simulator); ``implemented_faults()`` lets a self-test check that
every catalogued fault has exactly one implementation.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TypeVar

from encoder_conformance.sim.fault_catalogue import SIMULATOR_DEVIATIONS as FAULTS  # faults and conformant variants

T = TypeVar("T")

#: behaviour class -> [(fault name, mixin class)] in declaration order
_MIXINS: dict[type, list[tuple[str, type]]] = {}


class FaultSet:
    """The faults active in one simulated node."""

    def __init__(self, names: Iterable[str] = ()) -> None:
        self._active: set[str] = set()
        for name in names:
            self.enable(name)

    def enable(self, name: str) -> None:
        if name not in FAULTS:
            known = ", ".join(sorted(FAULTS))
            raise ValueError(f"unknown simulator fault {name!r}; known faults: {known}")
        self._active.add(name)

    def active(self, name: str) -> bool:
        if name not in FAULTS:  # a typo in the simulator must not silently disable a fault
            raise KeyError(name)
        return name in self._active

    @property
    def names(self) -> frozenset[str]:
        return frozenset(self._active)


def breaks(behaviour: type, name: str) -> Callable[[type[T]], type[T]]:
    """Class decorator: the decorated mixin is fault ``name`` of ``behaviour``."""
    if name not in FAULTS:
        raise KeyError(f"fault {name!r} is not in fault_catalogue.FAULTS")

    def register(mixin: type[T]) -> type[T]:
        _MIXINS.setdefault(behaviour, []).append((name, mixin))
        return mixin

    return register


def assemble(behaviour: type[T], faults: FaultSet) -> type[T]:
    """``behaviour`` itself, or a subclass with the mixins of the active faults that break it."""
    mixins = tuple(mixin for name, mixin in _MIXINS.get(behaviour, []) if name in faults.names)
    if not mixins:
        return behaviour
    return type(f"Faulty{behaviour.__name__}", (*mixins, behaviour), {})


def mixins_of(name: str) -> list[tuple[type, type]]:
    """(behaviour, mixin) for each behaviour fault ``name`` breaks (every behaviour module must have been
    imported)."""
    return [(behaviour, mixin) for behaviour, mixins in _MIXINS.items() for fault, mixin in mixins if fault == name]


def implemented_faults() -> dict[str, list[str]]:
    """fault name -> the behaviours it breaks (every behaviour module must have been imported)."""
    found: dict[str, list[str]] = {}
    for behaviour, mixins in _MIXINS.items():
        for name, _ in mixins:
            found.setdefault(name, []).append(behaviour.__name__)
    return found
