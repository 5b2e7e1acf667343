"""Store and restore variants beyond CiA 301 1010h/1011h, as two quirks describe them.

``reload_immediate``: 1011h sub-indices that load saved parameters at once, and parameter sets.

FAULHABER MC (2.4.1-2.4.3): 1010h.04/.05 save the App1/App2 parameter set; 1011h.04 reloads the
last user-saved application parameters, 1011h.05/.06 activate set 1/2, all without a reset.
CiA 301 §7.5.2.14 knows only restore-defaults that take effect after the next reset.

Set values live in the node's NVM under keys ``(set_number << 16 | index, sub)``, apart from the
ordinary stored values, so that a power cycle keeps them as the device keeps its sets.

``manufacturer_store_object``: a second 'save' object for manufacturer parameters (WayCon 2105h).

``store_object_reads_back``: 1010h/1011h subs read back a value other than CiA's word.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.sim.engine.hooks import NodeHooks
from encoder_conformance.sim.engine.nvm import Key, NonVolatileMemory
from encoder_conformance.sim.engine.object_store import ObjectStore


def set_slot(set_number: int, key: Key) -> Key:
    """The NVM key holding ``key``'s value in parameter set ``set_number``."""
    return (set_number << 16) | key[0], key[1]


@dataclass(frozen=True)
class ParameterSets:
    saves_set: dict[int, int]  # 1010h sub -> set number
    reloads: dict[int, int]  # 1011h sub -> 1010h sub whose saved values it loads at once
    set_objects: tuple[Key, ...]

    @classmethod
    def from_params(cls, params: fx.ReloadImmediate) -> ParameterSets:
        return cls(
            saves_set=dict(params.app_sets.saved_by),
            reloads=dict(params.reload_immediate),
            set_objects=tuple(params.app_sets.objects),
        )

    def handles(self, key: Key) -> bool:
        index, sub = key
        return (index == 0x1010 and sub in self.saves_set) or (index == 0x1011 and sub in self.reloads)

    def save_set(self, sub: int, store: ObjectStore, nvm: NonVolatileMemory) -> None:
        """1010h sub: copy the set objects' current values into their set."""
        number = self.saves_set[sub]
        values = store.nvm_values([key for key in self.set_objects if store.has(key)])
        nvm.put_many({set_slot(number, key): value for key, value in values.items()})

    def reload(self, sub: int, store: ObjectStore, nvm: NonVolatileMemory, default: Callable[[Key], Any],
               group_keys: Callable[[int], list[Key]]) -> None:
        """1011h sub: make the values saved by its 1010h sub current now (factory values if never saved)."""
        source = self.reloads[sub]
        if source in self.saves_set:
            number = self.saves_set[source]
            saved = {key: nvm.get(set_slot(number, key)) for key in self.set_objects if store.has(key)}
        else:
            saved = {key: nvm.get(key) for key in group_keys(source)}
        for key, value in saved.items():
            store.set(key, default(key) if value is None else value)


@dataclass(frozen=True)
class ManufacturerStoreObject:
    """Quirk ``manufacturer_store_object``: a second 'save' object for manufacturer parameters (WayCon 2105h)."""

    key: Key
    signature: int
    saves: tuple[Key, ...]
    wrong_signature_abort: int | None

    @classmethod
    def from_params(cls, params: fx.ManufacturerStoreObject) -> ManufacturerStoreObject:
        return cls(
            key=params.key,
            signature=params.signature,
            saves=tuple(params.saves),
            wrong_signature_abort=params.wrong_signature_abort,
        )


class ReadsBack:
    """Quirk ``store_object_reads_back``: 1010h/1011h subs read back a value other than CiA's word."""

    def __init__(self, params: fx.StoreObjectReadsBack) -> None:
        self._value = params.value

    def register(self, hooks: NodeHooks) -> None:
        hooks.sources.append(self.value)

    def value(self, key: Key, channel: str) -> int | None:
        return self._value if key[0] in (0x1010, 0x1011) and key[1] >= 1 else None
