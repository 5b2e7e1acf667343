"""The settings the encoder function depends on, read the same way from the twin's objects and from a device.

``EncoderDescription.of(profile)`` says where each role lives and which rules the device follows
(from its capabilities and typed quirks); ``read_settings(description, read)`` turns the values a
reader gives (the twin's object store, or SDO reads of a device) into the inputs of the pure
functions in ``position``, ``cam``, ``work_area`` and ``speed``. The twin and the suites both go
through here, so they cannot disagree about what a setting means.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction

import encoder_conformance.models.encoder.objects as od
from encoder_conformance.models.encoder.cam import Cam, CamChannel, CamRules
from encoder_conformance.models.encoder.limit_switch import LimitSwitchFlags
from encoder_conformance.models.encoder.objects import EncoderObjects
from encoder_conformance.models.encoder.position import (
    EncoderGeometry,
    Scaling,
    position_limits,
    position_span,
    signed_half_range,
)
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile

#: reads an integer entry (index, sub) as the device's data type gives it; None where it does not exist
Reader = Callable[[int, int], "int | None"]

#: physical steps per revolution when nothing says otherwise (the twin's default sensor)
DEFAULT_STEPS_PER_REV = 4096


@dataclass(frozen=True)
class EncoderDescription:
    """What does not change while a device runs: where the roles are, the device's rules."""

    objects: EncoderObjects
    multiturn: bool
    signed: bool
    scaling: bool
    preset: bool
    cam_channels: int
    cams_per_channel: int
    cam_rules: CamRules
    cam_low_above_high_documented: bool  # False: CiA 406 leaves it open, the outcome is only observed
    work_area: bool
    speed: bool
    speed_scaling_object: int | None
    flags: LimitSwitchFlags | None
    label_steps_per_rev: int | None  # simulator value / type-label default where 6501h is absent
    label_total_range: int | None
    physical_revolutions: int | None = None  # quirk physical_revolutions: more than 6502h shows
    module_max_is_range: bool = False  # quirk module_max_is_range: 650Ah sub 3 = range, not range - 1

    @classmethod
    def of(cls, profile: DeviceProfile) -> EncoderDescription:
        caps = profile.capabilities
        objects = EncoderObjects.of(profile)
        refuses_wrap = profile.params_of(fx.CamLowBelowHigh) is not None
        speed = profile.params_of(fx.SpeedScalingObject)
        flags = profile.params_of(fx.LimitSwitchFlags)
        revolutions = profile.params_of(fx.PhysicalRevolutions)
        values = profile.simulator.values
        steps = values.get("steps_per_rev")
        label_steps = _default_int(profile, objects.units_per_rev) if objects.relocated else None
        return cls(
            objects=objects,
            multiturn=caps.multiturn,
            signed=profile.has_effect(fx.SignedPositionRange) and caps.multiturn,
            scaling=caps.scaling,
            preset=caps.preset,
            cam_channels=caps.cam.channels if caps.cam else 0,
            cams_per_channel=caps.cam.cams_per_channel if caps.cam else 0,
            cam_rules=CamRules(low_above_high="refused" if refuses_wrap else "wrap"),
            cam_low_above_high_documented=refuses_wrap,
            work_area=caps.work_area,
            speed=caps.speed,
            speed_scaling_object=None if speed is None else speed.scaling_object,
            flags=None if flags is None else LimitSwitchFlags.from_params(flags),
            label_steps_per_rev=int(steps) if isinstance(steps, int) and steps else label_steps,
            label_total_range=_default_int(profile, objects.total_range) if objects.relocated else None,
            physical_revolutions=None if revolutions is None else revolutions.revolutions,
            module_max_is_range=profile.has_effect(fx.ModuleMaxIsRange),
        )


def _default_int(profile: DeviceProfile, index: int) -> int | None:
    entry = profile.entry(index, 0)
    return entry.default if entry is not None and isinstance(entry.default, int) else None


@dataclass(frozen=True)
class EncoderSettings:
    """Everything the position, CAM, work-area and speed values depend on, as read at one moment."""

    geometry: EncoderGeometry
    scaling: Scaling
    signed: bool
    cam_channels: tuple[CamChannel, ...] = ()
    areas: tuple[tuple[int, int], ...] = ()  # (low, high) per work-area channel
    speed_factor: Fraction = Fraction(1)

    @property
    def span(self) -> int:
        return position_span(self.geometry, self.scaling)

    def shown(self, unsigned_value: int) -> int:
        """A position 0 .. span - 1 as the device shows it (signed devices: two's complement halves)."""
        return signed_half_range(unsigned_value, self.span) if self.signed else unsigned_value

    def limits(self) -> tuple[int, int]:
        """Smallest and largest position value (650Ah sub 2 / sub 3)."""
        return position_limits(self.span, self.signed)


def read_geometry(description: EncoderDescription, read: Reader) -> EncoderGeometry:
    """Physical resolution: 6501h/6502h, else (relocated objects) the type-label defaults."""
    steps = (None if description.objects.relocated else read(od.SINGLE_TURN_RESOLUTION, 0)) \
        or description.label_steps_per_rev or DEFAULT_STEPS_PER_REV
    revolutions = 1
    if description.multiturn and description.physical_revolutions:
        revolutions = description.physical_revolutions
    elif description.multiturn:
        total = description.label_total_range
        revolutions = (None if description.objects.relocated else read(od.REVOLUTIONS, 0)) \
            or (total // steps if total else 0) or 1
    return EncoderGeometry(steps, revolutions)


def read_scaling(description: EncoderDescription, read: Reader, offset: int) -> Scaling:
    """6000h code sequence and scaling bits, 6001h, 6002h and the preset offset given."""
    objects = description.objects
    params = read(objects.operating, 0) or 0
    bit = objects.scaling_bit  # None (POSITAL): the scaling objects always apply
    enabled = bit is None or (bool(params >> bit & 1) and description.scaling)
    return Scaling(
        ccw=bool(params >> od.CODE_SEQUENCE_BIT & 1),
        enabled=enabled,
        units_per_rev=read(objects.units_per_rev, 0) or 0,
        total_range=read(objects.total_range, 0) or 0,
        offset=offset,
    )


def read_cam_channels(description: EncoderDescription, read: Reader) -> tuple[CamChannel, ...]:
    channels = []
    for channel in range(1, description.cam_channels + 1):
        cams = []
        for number in range(description.cams_per_channel):
            low, high, hysteresis = od.cam_limit_objects(number)
            cams.append(Cam(read(low, channel) or 0, read(high, channel) or 0, read(hysteresis, channel) or 0))
        channels.append(CamChannel(read(od.CAM_ENABLE, channel) or 0, read(od.CAM_POLARITY, channel) or 0,
                                   tuple(cams)))
    return tuple(channels)


def read_areas(description: EncoderDescription, read: Reader) -> tuple[tuple[int, int], ...]:
    if not description.work_area:
        return ()
    return ((read(od.AREA_LOW, 1) or 0, read(od.AREA_HIGH, 1) or 0),)


def read_speed_factor(description: EncoderDescription, read: Reader) -> Fraction:
    index = description.speed_scaling_object
    if index is None:
        return Fraction(1)
    numerator, denominator = read(index, 1), read(index, 2)
    return Fraction(numerator or 1, denominator or 1)


def read_settings(description: EncoderDescription, read: Reader, offset: int | None = None,
                  functions: bool = True) -> EncoderSettings:
    """The settings as ``read`` shows them; ``offset``: the preset offset where 6509h cannot be read;
    ``functions=False``: only what the position depends on (no CAM, work-area or speed objects read)."""
    if offset is None:
        offset = (None if description.objects.relocated else read(od.OFFSET, 0)) or 0
    return EncoderSettings(
        geometry=read_geometry(description, read),
        scaling=read_scaling(description, read, offset),
        signed=description.signed,
        cam_channels=read_cam_channels(description, read) if functions else (),
        areas=read_areas(description, read) if functions else (),
        speed_factor=read_speed_factor(description, read) if functions else Fraction(1),
    )
