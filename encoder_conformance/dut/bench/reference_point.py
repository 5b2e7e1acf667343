"""Where a device's position zero is, and putting it back: a preset moves a real machine's reference.

The reference point is the preset offset (6509h) where the device shows it, else the position
with the shaft at rest. A preset value object cannot simply be written back: writing it presets
again at the shaft's current angle. So the reference point is given back by presetting the value
that recreates the offset found (or, without 6509h, the position found); afterwards 6003h reads
that preset, not the one found, and the report says so. The run's custody records the reference
point as found and as stored (``reference_custody``); test fixtures use ``read_reference_point`` and
``restore_reference_point``.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.bench.encoder_access import EncoderAccess
from encoder_conformance.models.encoder import objects as od
from encoder_conformance.models.encoder.objects import EncoderObjects
from encoder_conformance.models.encoder.position import unsigned_in_span
from encoder_conformance.profile.schema import DeviceProfile

Key = tuple[int, int]


@dataclass(frozen=True)
class ReferencePoint:
    offset: int | None  # 6509h as read (None where the device has none)
    position: int  # the position read at the same time

    def as_dict(self) -> dict[str, int | None]:
        return asdict(self)

    @classmethod
    def from_dict(cls, raw: object) -> ReferencePoint | None:
        """The point as a snapshot file holds it (None: not recorded); TypeError if malformed."""
        if raw is None:
            return None
        if not (isinstance(raw, dict) and set(raw) == {"offset", "position"} and isinstance(raw["position"], int)
                and isinstance(raw["offset"], int | None)):
            raise TypeError(f"malformed reference point {raw!r}")
        return cls(raw["offset"], raw["position"])

    def describe(self) -> str:
        return f"offset 6509h = {self.offset}" if self.offset is not None else f"position {self.position} at rest"


@dataclass(frozen=True)
class Outcome:
    """What giving back a reference point did (None: nothing was needed) and what went wrong (None: nothing)."""

    done: str | None = None
    problem: str | None = None
    change: tuple[str, str, str] | None = None  # what differed: (label, wanted, seen before the preset)


def has_reference_point(profile: DeviceProfile) -> bool:
    """An encoder whose capabilities declare the preset, with a writable preset and a readable position."""
    objects = EncoderObjects.of(profile)
    preset, position = profile.entry(objects.preset, 0), profile.entry(objects.position, 0)
    return (profile.capabilities.encoder and profile.capabilities.preset and preset is not None and preset.writable
            and position is not None and position.readable)


def preset_keys(profile: DeviceProfile) -> list[Key]:
    """The preset objects (the preset role, 6009h where declared): writing one presets, so it has no value to give
    back; the custody gives back the reference point instead."""
    if not (profile.capabilities.encoder and profile.capabilities.preset):
        return []
    keys = [(EncoderObjects.of(profile).preset, 0), (od.HIGH_PRECISION_PRESET, 0)]
    return [key for key in keys if profile.entry(*key) is not None]


def read_reference_point(access: EncoderAccess) -> ReferencePoint:
    return ReferencePoint(access.offset(), access.position())


def restore_reference_point(access: EncoderAccess, found: ReferencePoint) -> str | None:
    """Preset so that the offset (or, without 6509h, the position) is as found; None or what went wrong.

    Call it after the scaling settings are back: the offset means something only in their units.
    """
    return give_back_reference_point(access, found).problem


def give_back_reference_point(access: EncoderAccess, target: ReferencePoint, settle: bool = False) -> Outcome:
    """Preset so that the offset (without 6509h: the position at rest) is ``target``'s, and check it.

    ``settle``: something was written just before, not through ``access``, which may hold the position at
    its old value for a while (quirk ``position_frozen_during_execution``): wait that long before reading
    the position. A preset that needs the scaling bit gets it from ``access.preset``.
    """
    if target.offset is not None and access.has_offset_object:
        return _give_back_offset(access, target.offset, settle)
    return _give_back_position(access, target.position, settle)


def same_offset(value: int | None, wanted: int, span: int) -> bool:
    """Whether two offsets are the same reference point (6509h may read either form modulo the range)."""
    return value is not None and unsigned_in_span(value - wanted, span) == 0


def _give_back_offset(access: EncoderAccess, offset: int, settle: bool) -> Outcome:
    now = access.offset()
    if now == offset or same_offset(now, offset, access.settings(functions=False).span):
        return Outcome()
    if settle:
        _settle(access)
    settings = access.settings(functions=False)
    span = settings.span
    assert now is not None  # has_offset_object
    unshifted = unsigned_in_span(access.position() - now, span)
    preset = settings.shown(unsigned_in_span(unshifted + offset, span))
    access.preset(preset)
    after = _offset_when(access, offset, span)
    done = (f"reference point: preset {preset} to give back offset 6509h = {offset}; "
            f"{_preset_reads(access)}")
    change = ("reference point (offset 6509h)", str(offset), str(now))
    if not same_offset(after, offset, span):
        return Outcome(done, f"reference point not given back: offset 6509h = {after} after presetting {preset}, "
                             f"{offset} wanted", change)
    return Outcome(done, change=change)


def _give_back_position(access: EncoderAccess, position: int, settle: bool) -> Outcome:
    if settle:
        _settle(access)
    now = access.position()
    if now == position:
        return Outcome()
    access.preset(position)
    reached = access.position_when(position, _late_s(access))
    done = (f"reference point: preset {position} to give back the position found at rest "
            f"({access.objects.position:04X}h = {position}; this assumes the shaft did not move since); "
            f"{_preset_reads(access)}")
    change = (f"reference point (position {access.objects.position:04X}h at rest)", str(position), str(now))
    if reached != position:
        return Outcome(done, f"reference point not given back: position {reached} after presetting {position} "
                             "(the position found at rest)", change)
    return Outcome(done, change=change)


def _preset_reads(access: EncoderAccess) -> str:
    index = access.objects.preset
    return f"{index:04X}h now reads {access.read_int(index, 0)}"


def _late_s(access: EncoderAccess) -> float:
    """How long to read again after the execution time the manual gives: a busy device (or a twin on a busy PC)
    may show the new value later; the reads stop as soon as it shows."""
    return access.dut.sdo_timeout


def _settle(access: EncoderAccess) -> None:
    """Wait out the longest execution time the manual gives for a write (0 s on most devices): writes made
    around ``access`` may hold the position at its old value until then."""
    freeze = access.freeze
    if freeze is not None:
        time.sleep(max([freeze.duration_ms, *freeze.durations_ms.values()]) / 1000)  # nothing shows it on the bus


def _offset_when(access: EncoderAccess, wanted: int, span: int) -> int | None:
    """6509h once the device executed the preset, read again until it is ``wanted`` or a late device had time
    enough (the last read)."""
    access.wait_until_executed()
    deadline = Deadline(_late_s(access))
    while True:
        value = access.offset()
        if same_offset(value, wanted, span) or deadline.expired():
            return value

