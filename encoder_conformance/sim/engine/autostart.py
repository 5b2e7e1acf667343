"""Quirk ``nmt_autostart_object``: after boot-up the device enters operational by itself when an
object holds a given value (instead of CiA 302-2 1F80h bit semantics). Its variant ``autostart_set_at_delivery``: the
object's default is that value (a device delivered self-starting)."""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.profile.quirk_effects import NmtAutostartObject
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.object_store import ObjectStore


class Autostart:
    """A behaviour: after the boot-up message, enter operational if the object says so."""

    def __init__(self, params: NmtAutostartObject, read: Callable[[int, int], int | None],
                 enter: Callable[[NmtState], None]) -> None:
        self._params = params
        self._read = read
        self._enter = enter

    def register(self, hooks: NodeHooks) -> None:
        hooks.booted.append(self.on_booted)

    def starts_itself(self) -> bool:
        params = self._params
        return self._read(params.index, params.subindex) == params.operational_value

    def on_booted(self) -> None:
        if self.starts_itself():
            self._enter(NmtState.OPERATIONAL)


@breaks(Autostart, "autostart_ignored")
class AutostartIgnored(Autostart):
    def starts_itself(self) -> bool:
        return False


@breaks(ObjectStore, "autostart_set_at_delivery")
class AutostartSetAtDelivery(ObjectStore):
    """A variant, not a fault: the autostart object's default is its operational value (a self-starting device)."""

    def default_of(self, key: Key, node_id: int) -> int | str:
        params = self.profile.params_of(NmtAutostartObject)
        if params is not None and key == (params.index, params.subindex):
            return params.operational_value
        return super().default_of(key, node_id)
