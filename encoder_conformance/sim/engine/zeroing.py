"""Quirk ``zeroing_object`` (SIKO 2002h): writing the trigger value zeroes the position, once per re-arm.

Writing ``trigger_value`` sets the position to 0 the way a preset of 0 does, if the preset value is
0 (the manual's condition) and the object was armed; writing ``rearm_value`` arms it again. The
twin starts armed (our inference: the manual does not say).
"""

from __future__ import annotations

from collections.abc import Callable

from encoder_conformance.profile.quirk_effects import ZeroingObject
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key


class Zeroing:
    """A behaviour: reacts to writes of the zeroing object."""

    def __init__(self, params: ZeroingObject, zero: Callable[[], None], preset_is_zero: Callable[[], bool]) -> None:
        self._key = (params.index, params.subindex)
        self._trigger = params.trigger_value
        self._rearm = params.rearm_value
        self._zero = zero
        self._preset_is_zero = preset_is_zero
        self.armed = True

    def register(self, hooks: NodeHooks) -> None:
        hooks.on_written(self.written, [self._key[0]])

    def written(self, key: Key, value: Value) -> None:
        if key != self._key or not isinstance(value, int):
            return
        if value == self._rearm:
            self.armed = True
        elif value == self._trigger and self.may_zero():
            self.armed = self.stays_armed()
            self._zero()

    def may_zero(self) -> bool:
        return self.armed and self._preset_is_zero()

    def stays_armed(self) -> bool:
        """After a zeroing the object needs the re-arm value first."""
        return False


@breaks(Zeroing, "zeroing_ignored")
class ZeroingIgnored(Zeroing):
    def may_zero(self) -> bool:
        return False


@breaks(Zeroing, "zeroing_rearm_ignored")
class ZeroingRearmIgnored(Zeroing):
    def stays_armed(self) -> bool:
        return True
