"""The measuring function of a simulated encoder: its objects in, the reference model's values out.

Every value (position, CAM state, work-area state, speed, preset offset) is computed by
``models.encoder`` from the settings in the twin's object store, read the way the suites read them
from a device. What stays here is the twin's own part: the shaft, the preset offset (6509h, or
internal on devices without it) kept in NVM whenever the preset object is stored (by a store
command, or by itself where it is persisted_by auto), SIKO's position freeze while a write executes
(``position_frozen_during_execution``) and the CAM history along the shaft's moves.

The decisions a fault may change are small methods (the scaling the position applies, the cam
settings the CAM logic applies, the position the CAMs and a TPDO see, the preset offset, the
speed, the area state); the faults are the classes at the bottom, each overriding one of them.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import replace

from encoder_conformance.models.encoder import objects as od
from encoder_conformance.models.encoder import position as pos
from encoder_conformance.models.encoder.cam import Cam, CamChannel
from encoder_conformance.models.encoder.freeze import FreezeRule
from encoder_conformance.models.encoder.reference import EncoderReference
from encoder_conformance.models.encoder.settings import EncoderDescription, EncoderSettings, read_settings
from encoder_conformance.models.encoder.speed import speed_value
from encoder_conformance.models.encoder.work_area import ABOVE, BELOW
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.nvm import Key, NonVolatileMemory
from encoder_conformance.sim.engine.object_store import ObjectStore
from encoder_conformance.sim.engine.scheduler import DeadlineScheduler
from encoder_conformance.sim.engine.shaft import Shaft

#: NVM slot (index 0 is no object) for the preset offset (6509h's value, or the internal one without 6509h)
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
        # settings() remembered with what it was computed from (see settings): keys read, their values, result
        self._settings_read: list[Key] = []
        self._settings_memo: tuple[tuple[object, ...], EncoderSettings] | None = None
        self.reference = EncoderReference(self.settings(), self.description.cam_rules)
        # the position shown while a write executes, and until when (monotonic): judged by the clock when the
        # position is read, not by a timer job, so a twin whose timing thread runs late on a loaded host does
        # not keep its position frozen longer than the manual says
        self._frozen: int | None = None
        self._frozen_until = 0.0
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
        return datatypes.as_signed(self.store.entries[key].type, value)

    def settings(self) -> EncoderSettings:
        """The settings as the function applies them: the stored ones, through the decisions below.

        Computed again only when a value it read last time (or the internal offset) changed: every position,
        speed or CAM read needs them, and reading ~35 objects through the model cost ~70 µs a read, ~10 % of
        the twin's CPU in a WDGA run. Sound because the computation is a function of the values it reads (the
        entries' types and the decisions below do not change while the node lives): where none of them changed,
        it would read the same keys and give the same result."""
        values = self.store.values
        fingerprint = (self._offset, tuple(map(values.get, self._settings_read)))
        memo = self._settings_memo
        if memo is not None and memo[0] == fingerprint:
            return memo[1]
        read: list[Key] = []
        settings = self._read_settings(read)
        self._settings_read = read
        self._settings_memo = ((self._offset, tuple(map(values.get, read))), settings)
        return settings

    def _read_settings(self, read: list[Key]) -> EncoderSettings:
        """``settings()`` computed from the store; the keys it reads are appended to ``read``."""

        def read_int(index: int, sub: int = 0) -> int | None:
            read.append((index, sub))
            return self.read_int(index, sub)

        in_object = self.offset_in_object()
        stored = read_settings(self.description, read_int, None if in_object else self._offset)
        scaling = stored.scaling
        if in_object and stored.span:  # 6509h may read negative (SIGNED32); the arithmetic wants 0..span-1
            scaling = replace(scaling, offset=scaling.offset % stored.span)
        return replace(stored, scaling=self.position_scaling(scaling, stored.geometry),
                       cam_channels=tuple(self.cam_channel(channel) for channel in stored.cam_channels))

    def _current(self) -> EncoderReference:
        """The reference with the settings as they are now (the CAM history kept)."""
        self.reference.settings = self.settings()
        return self.reference

    # -- decisions (a fault overrides one) ---------------------------------------------------
    def offset_in_object(self) -> bool:
        """Is the preset offset kept in 6509h (else internally, in NVM: devices without 6509h)?"""
        return self.store.has((od.OFFSET, 0))

    def position_scaling(self, scaling: pos.Scaling, geometry: pos.EncoderGeometry) -> pos.Scaling:
        """Code sequence, scaling and measuring range as the position applies them."""
        return scaling

    def cam_channel(self, channel: CamChannel) -> CamChannel:
        """A CAM channel's enable, polarity, limits and hysteresis as the CAM logic applies them."""
        return channel

    def cam_position(self) -> int:
        """The position the CAMs compare with their limits."""
        return self.position()

    def channel_position(self, channel: str) -> int:
        """The position value as ``channel`` (sdo, tpdo) shows it."""
        return self.position()

    def preset_offset(self, preset: int, unshifted: int, span: int) -> int:
        """The offset a preset produces where the position reads ``unshifted`` without offset."""
        return pos.preset_offset(preset, unshifted, span)

    def apply_preset(self, preset: int) -> None:
        """A preset was written: keep the offset that makes the position read ``preset`` here."""
        settings = self._current().settings
        unshifted = pos.unshifted_position(self.shaft.turns(), settings.geometry, settings.scaling)
        offset = self.preset_offset(preset, unshifted, settings.span)
        if self.offset_in_object():
            self.store.set((od.OFFSET, 0), offset)
        else:
            self._offset = offset

    def speed(self) -> int:
        """6030h: measuring units per second (the reference's rule)."""
        return self._current().speed(self.shaft.speed)

    def area_state(self) -> int:
        """6400h sub 1 for the current position."""
        return self._current().area_state(self.position())

    # -- values ------------------------------------------------------------------------------
    def position(self) -> int:
        """The position value (frozen while a write is processed, if the profile says so)."""
        if self._frozen is not None and time.monotonic() < self._frozen_until:
            return self._frozen
        self._frozen = None
        return self._current().position(self.shaft.turns())

    def raw_counts(self) -> int:
        """The sensor's physical counts (no code sequence, scaling or offset)."""
        return pos.raw_counts(self.shaft.turns(), self.settings().geometry)

    def follow_shaft(self) -> None:
        """The shaft moved: the CAM history sees the position it reached."""
        if self.description.cam_channels:
            self._cam_state(1)

    def _cam_state(self, channel: int) -> int:
        """6300h sub ``channel``; every channel's history follows the position."""
        reference, position = self._current(), self.cam_position()
        channels = range(1, len(reference.settings.cam_channels) + 1)
        states = [reference.cam_state(position, number) for number in channels]
        return states[channel - 1]

    def value(self, key: Key, channel: str) -> int | None:
        """Computed values (position, speed, CAM and area state, mirrors) as ``channel`` (sdo, tpdo) shows them."""
        index, sub = key
        if key in ((self.objects.position, 0), (0x6008, 0)):
            position = self.channel_position(channel)
            flags = self.description.flags
            if flags is not None and index == flags.value_object and channel in flags.channels:
                return self.process_value(position)
            return position
        if index == od.SPEED and sub >= 1 and self.description.speed:
            return self.speed()
        if index == od.CAM_STATE and 1 <= sub <= self.description.cam_channels:
            return self._cam_state(sub)
        if index == od.AREA_STATE and sub == 1 and self.description.work_area:
            return self.area_state()
        if key == (od.OPERATING_STATUS, 0) and self.store.has((0x6000, 0)):
            return self.operating_status()
        if index == od.MODULE_IDENTIFICATION and sub in (2, 3) and self._follows_range(key):
            return self.module_limits()[sub - 2]
        return None

    def _follows_range(self, key: Key) -> bool:
        """650Ah sub 2/3 follow the measuring range where the profile has them read-only, not constant."""
        entry = self.store.entries.get(key)
        return entry is not None and entry.access == "ro"

    def module_limits(self) -> tuple[int, int]:
        """650Ah sub 2 / sub 3: the smallest and largest position value of the range in use (sub 3 one more
        where the profile says so, quirk ``module_max_is_range``)."""
        low, high = self.settings().limits()
        return low, high + 1 if self.description.module_max_is_range else high

    def process_value(self, position: int) -> int:
        """The position with the limit-switch flag bits (quirk ``limit_switch_flags``)."""
        assert self.description.flags is not None
        return self.description.flags.apply(position, self.read_int)

    def operating_status(self) -> int | None:
        """6500h: the 6000h settings in use."""
        value = self.store.get((0x6000, 0))
        return value if isinstance(value, int) else None

    # -- writes ------------------------------------------------------------------------------
    def on_write(self, key: Key, value: int | float | str | bytes) -> None:
        """A write passed all checks: freeze the position if the profile says so, apply a preset."""
        duration = self.freeze_rule.duration_s(key[0], value) if self.freeze_rule else 0.0
        if duration > 0:
            self._frozen = self.position()  # the value shown now (still the frozen one inside a running freeze)
            self._frozen_until = max(self._frozen_until, time.monotonic() + duration)
        if key == (self.objects.preset, 0) and isinstance(value, int):
            self.apply_preset(datatypes.as_signed(self.store.entries[key].type, value))

    def thaw(self) -> None:
        """End a freeze: the position follows the shaft again."""
        self._frozen = None
        self._frozen_until = 0.0

    # -- persistence of the preset offset --------------------------------------------------
    def reload(self, nvm: NonVolatileMemory) -> None:
        """A (re)start: the stored offset (6509h keeps its default where none was stored)."""
        self.thaw()
        self.reference.forget_cam_history()
        stored = nvm.get(OFFSET_KEY)
        if self.offset_in_object():
            if isinstance(stored, int):
                self.store.set((od.OFFSET, 0), stored)
        else:
            self._offset = stored if isinstance(stored, int) else 0

    def persist(self, nvm: NonVolatileMemory, stored: Iterable[Key] | None = None) -> None:
        """Keep the offset where the preset object was just stored (``stored``: the keys stored, None: all)."""
        if stored is not None and (self.objects.preset, 0) not in stored:
            return
        offset = self.store.get((od.OFFSET, 0)) if self.offset_in_object() else self._offset
        if isinstance(offset, int):
            nvm.put_many({OFFSET_KEY: offset})

    def forget(self, nvm: NonVolatileMemory, cleared: Iterable[Key] | None = None) -> None:
        """Restore defaults: the stored offset goes with the preset object (``cleared``: its keys, None: all)."""
        if cleared is not None and (self.objects.preset, 0) not in cleared:
            return
        if OFFSET_KEY in nvm:
            nvm.remove_many([OFFSET_KEY])


# -- faults: position, preset, speed (suite test_encoder_position) ------------------------------
@breaks(EncoderFunction, "preset_ignored")
class PresetIgnored(EncoderFunction):
    def apply_preset(self, preset: int) -> None:
        """The write is confirmed and stored in 6003h; the offset stays as it was."""


@breaks(EncoderFunction, "preset_wrong_sign")
class PresetWrongSign(EncoderFunction):
    def preset_offset(self, preset: int, unshifted: int, span: int) -> int:
        return pos.preset_offset(unshifted, preset, span)  # unshifted - preset


@breaks(EncoderFunction, "wrap_wrong_value")
class WrapsOneEarly(EncoderFunction):
    def position_scaling(self, scaling: pos.Scaling, geometry: pos.EncoderGeometry) -> pos.Scaling:
        """A measuring range one short: scaling 1:1 where it is off, so the physical counts wrap early too."""
        scaling = super().position_scaling(scaling, geometry)
        span = pos.position_span(geometry, scaling)
        if not (scaling.enabled and scaling.units_per_rev > 0):
            scaling = replace(scaling, enabled=True, units_per_rev=geometry.steps_per_rev)
        return replace(scaling, total_range=span - 1)


@breaks(EncoderFunction, "direction_ignored")
class DirectionIgnored(EncoderFunction):
    def position_scaling(self, scaling: pos.Scaling, geometry: pos.EncoderGeometry) -> pos.Scaling:
        return replace(super().position_scaling(scaling, geometry), ccw=False)


@breaks(EncoderFunction, "scaling_ignored")
class ScalingIgnored(EncoderFunction):
    def position_scaling(self, scaling: pos.Scaling, geometry: pos.EncoderGeometry) -> pos.Scaling:
        return replace(super().position_scaling(scaling, geometry), enabled=False)


@breaks(EncoderFunction, "offset_not_shown")
class OffsetNotShown(EncoderFunction):
    def offset_in_object(self) -> bool:
        return False  # the offset is kept internally; 6509h keeps what it holds (0)


@breaks(EncoderFunction, "speed_wrong_unit")
class SpeedInRpm(EncoderFunction):
    def speed(self) -> int:
        return speed_value(self.shaft.speed * 60, 1, self.settings().scaling.ccw)


@breaks(EncoderFunction, "module_identification_stale")
class ModuleIdentificationStale(EncoderFunction):
    def module_limits(self) -> tuple[int, int]:
        low, high = (self.store.default_of((od.MODULE_IDENTIFICATION, sub), 0) for sub in (2, 3))
        return (low if isinstance(low, int) else 0), (high if isinstance(high, int) else 0)


@breaks(EncoderFunction, "limit_switch_flags_ignored")
class LimitSwitchFlagsIgnored(EncoderFunction):
    def process_value(self, position: int) -> int:
        assert self.description.flags is not None
        return position & self.description.flags.position_mask


@breaks(EncoderFunction, "operating_status_stale")
class OperatingStatusStale(EncoderFunction):
    def operating_status(self) -> int | None:
        value = self.store.default_of((0x6000, 0), 0)
        return value if isinstance(value, int) else None


@breaks(EncoderFunction, "tpdo_position_unscaled")
class TpdoPositionUnscaled(EncoderFunction):
    def channel_position(self, channel: str) -> int:
        return self.raw_counts() if channel == "tpdo" else super().channel_position(channel)


# -- faults: CAM (suite test_cam) and work area (suite test_work_area) ----------------------------
@breaks(EncoderFunction, "cam_polarity_ignored")
class CamPolarityIgnored(EncoderFunction):
    def cam_channel(self, channel: CamChannel) -> CamChannel:
        return replace(super().cam_channel(channel), polarity=0)


@breaks(EncoderFunction, "cam_hysteresis_ignored")
class CamHysteresisIgnored(EncoderFunction):
    def cam_channel(self, channel: CamChannel) -> CamChannel:
        channel = super().cam_channel(channel)
        return replace(channel, cams=tuple(replace(cam, hysteresis=0) for cam in channel.cams))


@breaks(EncoderFunction, "cam_edge_off_by_one")
class CamHighEdgeExcluded(EncoderFunction):
    def cam_channel(self, channel: CamChannel) -> CamChannel:
        """Each window ends one before its high limit (a one-point window keeps its point)."""
        channel = super().cam_channel(channel)
        return replace(channel, cams=tuple(Cam(cam.low, cam.high - 1, cam.hysteresis) if cam.high > cam.low else cam
                                           for cam in channel.cams))


@breaks(EncoderFunction, "cam_on_unscaled_value")
class CamOnUnscaledValue(EncoderFunction):
    def cam_position(self) -> int:
        return self.raw_counts()


@breaks(EncoderFunction, "cam_enable_ignored")
class CamEnableIgnored(EncoderFunction):
    def cam_channel(self, channel: CamChannel) -> CamChannel:
        channel = super().cam_channel(channel)
        return replace(channel, enable=(1 << len(channel.cams)) - 1)


@breaks(EncoderFunction, "work_area_flags_swapped")
class WorkAreaFlagsSwapped(EncoderFunction):
    def area_state(self) -> int:
        state = super().area_state()
        return state ^ (ABOVE | BELOW) if state & (ABOVE | BELOW) else state
