"""The measuring function of a simulated encoder: its objects in, the reference model's values out.

Every value (position, CAM state, work-area state, speed, preset offset) is computed by
``encoder_model`` from the settings in the twin's object store, read the way the suites read them
from a device. What stays here is the twin's own part: the shaft, the preset offset of devices
without 6509h (kept in NVM), SIKO's position freeze while a write executes
(``position_frozen_during_execution``) and the CAM history along the shaft's moves.
"""

from __future__ import annotations

from dataclasses import replace

from ..encoder_model import objects as od
from ..encoder_model.freeze import FreezeRule
from ..encoder_model.reference import EncoderReference
from ..encoder_model.settings import EncoderDescription, EncoderSettings, read_settings
from ..profile import datatypes
from ..profile.model import DeviceProfile
from .nvm import Key, NonVolatileMemory
from .object_store import ObjectStore
from .scheduler import DeadlineScheduler, JobHandle
from .shaft import Shaft

#: NVM slot (index 0 is no object) for the preset offset of devices without 6509h
OFFSET_KEY: Key = (0x0000, 0)


class EncoderFunction:
    """Position, preset, CAM, work area and speed of one simulated encoder."""

    def __init__(self, profile: DeviceProfile, store: ObjectStore, shaft: Shaft, scheduler: DeadlineScheduler) -> None:
        self.profile = profile
        self.store = store
        self.shaft = shaft
        self.scheduler = scheduler
        self.description = EncoderDescription.of(profile)
        self.objects = self.description.objects
        self.freeze_rule = FreezeRule.of(profile)
        self._offset = 0  # preset offset when the profile has no 6509h
        self.reference = EncoderReference(self.settings(), self.description.cam_rules)
        self._frozen: int | None = None
        self._thaw_job: JobHandle | None = None
        shaft.listeners.append(self.follow_shaft)

    # -- reading the settings from the object store -----------------------------------------
    def read_int(self, index: int, sub: int = 0) -> int | None:
        """An integer entry as its data type gives it (SIGNED types negative), None where absent."""
        key = (index, sub)
        if not self.store.has(key):
            return None
        value = self.store.get(key)
        if not isinstance(value, int):
            return None
        entry = self.store.entries[key]
        size = datatypes.size_bytes(entry.type)
        if size and datatypes.is_signed(entry.type) and value >= 1 << (8 * size - 1):
            return value - (1 << (8 * size))
        return value

    def settings(self) -> EncoderSettings:
        has_offset_object = self.store.has((od.OFFSET, 0))
        settings = read_settings(self.description, self.read_int, None if has_offset_object else self._offset)
        if has_offset_object and settings.span:  # 6509h may read negative (SIGNED32); the arithmetic wants 0..span-1
            offset = settings.scaling.offset % settings.span
            settings = replace(settings, scaling=replace(settings.scaling, offset=offset))
        return settings

    def _current(self) -> EncoderReference:
        """The reference with the settings as they are now (the CAM history kept)."""
        self.reference.settings = self.settings()
        return self.reference

    # -- values ------------------------------------------------------------------------------
    def position(self) -> int:
        """The position value (frozen while a write is processed, if the profile says so)."""
        return self._frozen if self._frozen is not None else self._current().position(self.shaft.turns())

    def follow_shaft(self) -> None:
        """The shaft moved: the CAM history sees the position it reached."""
        if self.description.cam_channels:
            self._cam_state(1)

    def _cam_state(self, channel: int) -> int:
        """6300h sub ``channel``; every channel's history follows the position."""
        reference, position = self._current(), self.position()
        channels = range(1, len(reference.settings.cam_channels) + 1)
        states = [reference.cam_state(position, number) for number in channels]
        return states[channel - 1]

    def value(self, key: Key, channel: str) -> int | None:
        """Computed values (position, speed, CAM and area state, mirrors) as ``channel`` (sdo, tpdo) shows them."""
        index, sub = key
        if key in ((self.objects.position, 0), (0x6008, 0)):
            position = self.position()
            flags = self.description.flags
            if flags is not None and index == flags.value_object and channel in flags.channels:
                return flags.apply(position, self.read_int)
            return position
        if index == od.SPEED and sub >= 1 and self.description.speed:
            return self._current().speed(self.shaft.speed)
        if index == od.CAM_STATE and 1 <= sub <= self.description.cam_channels:
            return self._cam_state(sub)
        if index == od.AREA_STATE and sub == 1 and self.description.work_area:
            return self._current().area_state(self.position())
        if key == (od.OPERATING_STATUS, 0) and self.store.has((0x6000, 0)):
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
            self._preset(self._signed_preset(value))

    def _signed_preset(self, value: int) -> int:
        entry = self.store.entries.get((self.objects.preset, 0))
        size = datatypes.size_bytes(entry.type) if entry is not None else None
        if entry is not None and size and datatypes.is_signed(entry.type) and value >= 1 << (8 * size - 1):
            return value - (1 << (8 * size))
        return value

    def thaw(self) -> None:
        """End a freeze: the position follows the shaft again."""
        if self._thaw_job is not None:
            self._thaw_job.cancel()
            self._thaw_job = None
        self._frozen = None

    def _preset(self, preset: int) -> None:
        offset = self._current().offset_for_preset(preset, self.shaft.turns())
        if self.store.has((od.OFFSET, 0)):
            self.store.set((od.OFFSET, 0), offset)
        else:
            self._offset = offset

    # -- persistence of the internal preset offset (devices without 6509h) -------------------
    def reload(self, nvm: NonVolatileMemory) -> None:
        self.thaw()
        self.reference.forget_cam_history()
        stored = nvm.get(OFFSET_KEY)
        self._offset = stored if isinstance(stored, int) else 0

    def persist(self, nvm: NonVolatileMemory) -> None:
        if not self.store.has((od.OFFSET, 0)):
            nvm.put_many({OFFSET_KEY: self._offset})

    def forget(self, nvm: NonVolatileMemory) -> None:
        if OFFSET_KEY in nvm:
            nvm.remove_many([OFFSET_KEY])
