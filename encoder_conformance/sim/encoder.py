"""The measuring function of a simulated encoder: shaft angle -> the values the OD and TPDOs show.

CiA 406 objects (6000h..6004h, 6509h) by default; the quirk effects that change them are
applied here: ``manufacturer_encoder_objects`` (the same function in manufacturer objects),
``signed_position_range``, ``limit_switch_flags`` and ``position_frozen_during_execution``.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..profile import quirk_effects as fx
from ..profile.model import DeviceProfile
from .limit_switch import LimitSwitchFlags
from .nvm import Key, NonVolatileMemory
from .object_store import ObjectStore
from .position import (
    EncoderGeometry,
    Scaling,
    position_span,
    position_value,
    signed_half_range,
    unshifted_position,
)
from .scheduler import DeadlineScheduler, JobHandle
from .shaft import Shaft

#: NVM slot (index 0 is no object) for the preset offset of devices without 6509h
OFFSET_KEY: Key = (0x0000, 0)


@dataclass(frozen=True)
class EncoderObjects:
    """Where the CiA 406 roles live on this device (quirk effect ``manufacturer_encoder_objects``)."""

    operating: int = 0x6000
    units_per_rev: int = 0x6001
    total_range: int = 0x6002
    preset: int = 0x6003
    position: int = 0x6004
    scaling_bit: int | None = 2  # None: the scaling objects always apply

    @classmethod
    def of(cls, profile: DeviceProfile) -> EncoderObjects:
        params = profile.params_of(fx.ManufacturerEncoderObjects)
        if params is None:
            return cls()
        role = {cia: own for own, cia in params.equivalents.items()}
        return cls(
            operating=role.get(0x6000, 0x6000),
            units_per_rev=role.get(0x6001, 0x6001),
            total_range=role.get(0x6002, 0x6002),
            preset=role.get(0x6003, 0x6003),
            position=role.get(0x6004, 0x6004),
            scaling_bit=params.scaling_bit,
        )


@dataclass(frozen=True)
class FreezeRule:
    """How long the position stays frozen after a write (quirk ``position_frozen_during_execution``)."""

    objects: frozenset[int]
    duration_ms: float
    durations_ms: dict[str, float]

    @classmethod
    def from_params(cls, params: fx.PositionFrozenDuringExecution) -> FreezeRule:
        durations = {k.lower(): v for k, v in params.durations_ms.items()}
        return cls(params.indices, params.duration_ms, durations)

    def duration_s(self, index: int, value: object) -> float:
        """0 when a write to ``index`` does not freeze the position."""
        if index not in self.objects:
            return 0.0
        name = f"0x{index:04x}"
        if isinstance(value, int) and value & 0x04 and f"{name}.scaling_bit_set" in self.durations_ms:
            return self.durations_ms[f"{name}.scaling_bit_set"] / 1000
        return self.durations_ms.get(name, self.duration_ms) / 1000


class EncoderFunction:
    """Position, speed and preset of one simulated encoder."""

    def __init__(self, profile: DeviceProfile, store: ObjectStore, shaft: Shaft, scheduler: DeadlineScheduler) -> None:
        self.profile = profile
        self.store = store
        self.shaft = shaft
        self.scheduler = scheduler
        self.objects = EncoderObjects.of(profile)
        self.signed = profile.has_effect(fx.SignedPositionRange) and profile.capabilities.multiturn
        flags = profile.params_of(fx.LimitSwitchFlags)
        self.flags = None if flags is None else LimitSwitchFlags.from_params(flags)
        freeze = profile.params_of(fx.PositionFrozenDuringExecution)
        self.freeze_rule = None if freeze is None else FreezeRule.from_params(freeze)
        self._offset = 0  # preset offset when the profile has no 6509h
        self._frozen: int | None = None
        self._thaw_job: JobHandle | None = None

    def read_int(self, index: int, sub: int = 0) -> int | None:
        key = (index, sub)
        if not self.store.has(key):
            return None
        value = self.store.get(key)
        return value if isinstance(value, int) else None

    def _default_int(self, index: int) -> int | None:
        if not self.store.has((index, 0)):
            return None
        value = self.store.default_of((index, 0), 0)
        return value if isinstance(value, int) else None

    # -- geometry and scaling --------------------------------------------------------------
    def geometry(self) -> EncoderGeometry:
        """Physical resolution: 6501h/6502h, else (relocated objects) the type-label defaults."""
        relocated = self.objects.position != 0x6004
        label_steps = self._default_int(self.objects.units_per_rev) if relocated else None
        steps = (self.read_int(0x6501) or int(self.profile.simulator.values.get("steps_per_rev", 0))
                 or label_steps or 4096)
        revolutions = 1
        if self.profile.capabilities.multiturn:
            total = self._default_int(self.objects.total_range) if relocated else None
            revolutions = self.read_int(0x6502) or (total // steps if total else 0) or 1
        return EncoderGeometry(steps, revolutions)

    def scaling(self) -> Scaling:
        objects = self.objects
        params = self.read_int(objects.operating) or 0
        if objects.scaling_bit is None:
            enabled = True
        else:
            enabled = bool(params >> objects.scaling_bit & 1) and self.profile.capabilities.scaling
        return Scaling(
            ccw=bool(params & 0x01),
            enabled=enabled,
            units_per_rev=self.read_int(objects.units_per_rev) or 0,
            total_range=self.read_int(objects.total_range) or 0,
            offset=self._preset_offset(),
        )

    def _preset_offset(self) -> int:
        if self.store.has((0x6509, 0)):
            value = self.read_int(0x6509) or 0
            return value - (1 << 32) if value >= 1 << 31 else value
        return self._offset

    # -- values ------------------------------------------------------------------------------
    def position(self) -> int:
        """The position value (frozen while a write is processed, if the profile says so)."""
        return self._frozen if self._frozen is not None else self._live_position()

    def _live_position(self) -> int:
        geometry, scaling = self.geometry(), self.scaling()
        value = position_value(self.shaft.turns(), geometry, scaling)
        return signed_half_range(value, position_span(geometry, scaling)) if self.signed else value

    def value(self, key: Key, channel: str) -> int | None:
        """Computed values (position, speed, mirrors) as ``channel`` (sdo, tpdo) shows them; None otherwise."""
        if key in ((self.objects.position, 0), (0x6008, 0)):
            position = self.position()
            flags = self.flags
            if flags is not None and key[0] == flags.value_object and channel in flags.channels:
                return flags.apply(position, self.read_int)
            return position
        if key == (0x6030, 1):
            units = self.scaling().units_per_rev or self.geometry().steps_per_rev
            return max(-32768, min(32767, round(self.shaft.speed * units)))
        if key == (0x6500, 0) and self.store.has((0x6000, 0)):
            value = self.store.get((0x6000, 0))
            return value if isinstance(value, int) else None
        return None

    # -- writes ------------------------------------------------------------------------------
    def on_write(self, key: Key, value: int | str | bytes) -> None:
        """A write passed all checks: freeze the position if the profile says so, apply a preset."""
        duration = self.freeze_rule.duration_s(key[0], value) if self.freeze_rule else 0.0
        if duration > 0:
            if self._frozen is None:
                self._frozen = self.position()
            if self._thaw_job is not None:
                self._thaw_job.cancel()
            self._thaw_job = self.scheduler.call_later(duration, self.thaw)
        if key == (self.objects.preset, 0) and isinstance(value, int):
            self._preset(value)

    def thaw(self) -> None:
        """End a freeze: the position follows the shaft again."""
        if self._thaw_job is not None:
            self._thaw_job.cancel()
            self._thaw_job = None
        self._frozen = None

    def _preset(self, preset: int) -> None:
        geometry, scaling = self.geometry(), self.scaling()
        before = unshifted_position(self.shaft.turns(), geometry, scaling)
        span = position_span(geometry, scaling)
        offset = (preset - before) % span if span else preset - before
        if self.store.has((0x6509, 0)):
            self.store.set((0x6509, 0), offset)
        else:
            self._offset = offset

    # -- persistence of the internal preset offset (devices without 6509h) -------------------
    def reload(self, nvm: NonVolatileMemory) -> None:
        self.thaw()
        stored = nvm.get(OFFSET_KEY)
        self._offset = stored if isinstance(stored, int) else 0

    def persist(self, nvm: NonVolatileMemory) -> None:
        if not self.store.has((0x6509, 0)):
            nvm.put_many({OFFSET_KEY: self._offset})

    def forget(self, nvm: NonVolatileMemory) -> None:
        if OFFSET_KEY in nvm:
            nvm.remove_many([OFFSET_KEY])
