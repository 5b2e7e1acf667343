"""Where a device's position zero is, and putting it back: a preset moves a real machine's reference.

The reference point is the preset offset (6509h) where the device shows it, else the position
with the shaft at rest. A preset value object cannot simply be written back: writing it presets
again at the shaft's current angle. So the reference point is given back by presetting the value
that recreates the offset found (or, without 6509h, the position found); afterwards 6003h reads
that preset, not the one found, and the report says so.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from ..encoder_model.position import unsigned_in_span
from .encoder_access import EncoderAccess


@dataclass(frozen=True)
class ReferencePoint:
    offset: int | None  # 6509h as read (None where the device has none)
    position: int  # the position read at the same time

    def as_dict(self) -> dict[str, int | None]:
        return asdict(self)


def read_reference_point(access: EncoderAccess) -> ReferencePoint:
    return ReferencePoint(access.offset(), access.position())


def restore_reference_point(access: EncoderAccess, found: ReferencePoint) -> str | None:
    """Preset so that the offset (or, without 6509h, the position) is as found; None or what went wrong.

    Call it after the scaling settings are back: the offset means something only in their units.
    """
    span = access.settings(functions=False).span
    if found.offset is not None:
        now = access.offset()
        assert now is not None
        if unsigned_in_span(now - found.offset, span) == 0:
            return None
        unshifted = unsigned_in_span(access.position() - now, span)
        target = access.settings(functions=False).shown(unsigned_in_span(unshifted + found.offset, span))
        access.preset(target)
        after = access.offset()
        if after is None or unsigned_in_span(after - found.offset, span) != 0:
            return f"offset 6509h = {after} after presetting {target}, {found.offset} was found"
        return None
    if access.position() == found.position:
        return None
    access.preset(found.position)
    reached = access.position_when(found.position)
    if reached != found.position:
        return f"position {reached} after presetting {found.position} (the position found at rest)"
    return None
