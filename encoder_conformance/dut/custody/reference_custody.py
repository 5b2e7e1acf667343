"""The reference point in the run's custody: recorded at ``take``, given back by presetting at ``give_back``.

A preset object (6003h or the manufacturer's, 6009h) has no value to write back: writing it presets
again at the shaft's current angle (``snapshot.custody_keys`` leaves it out). The custody records the
reference point (``reference_point``: 6509h, or the position at rest) as found and as stored. In the
stored phase it presets the stored one again where the run could have stored another, and stores
it with the preset object's own store command; after the values in use are back (scaling first: the
offset is in scaled units) it presets the one found.
"""

from __future__ import annotations

from collections.abc import Mapping

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import STORE_PARAMETERS
from encoder_conformance.dut.bench.encoder_access import EncoderAccess
from encoder_conformance.dut.bench.reference_point import (
    Outcome,
    ReferencePoint,
    give_back_reference_point,
    has_reference_point,
    same_offset,
)
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.sdo.sdo_frames import abort_name
from encoder_conformance.dut.store.persist import CannotPersist, store_commands_for
from encoder_conformance.dut.store.store_watch import AUTO_STORED

Key = tuple[int, int]


class ReferenceCustody:
    """Reads and gives back one device's reference point (nothing where the profile declares no preset)."""

    def __init__(self, dut: DeviceLink) -> None:
        self.profile = dut.profile
        self.access = EncoderAccess(dut) if has_reference_point(dut.profile) else None

    @property
    def preset_key(self) -> Key | None:
        return None if self.access is None else (self.access.objects.preset, 0)

    def read(self) -> ReferencePoint | None:
        """The reference point now (None: no preset on this device, or the device refuses a read)."""
        if self.access is None:
            return None
        try:
            return ReferencePoint(self.access.offset(), self.access.position())
        except SdoAbortedError:
            return None

    def store_may_have_changed(self, counts: Mapping[str, int], history_unknown: bool) -> bool:
        """Whether the run could have stored another reference point: a store command that covers the preset
        object (or restores defaults) was sent, or the preset object stores itself and such writes were sent.
        ``history_unknown`` (``restore --from``): what the run sent is not known, so it may have."""
        key = self.preset_key
        if key is None:
            return False
        if history_unknown:
            return True
        try:
            commands = store_commands_for(self.profile, [key])
        except CannotPersist:
            return any(kind.startswith(("store ", "restore defaults")) for kind in counts)
        if not commands:  # persisted_by auto
            return AUTO_STORED in counts or any(kind.startswith("restore defaults") for kind in counts)
        covering = {f"store {c.index:04X}h.{c.sub:02X}" for c in commands} | {f"store {STORE_PARAMETERS:04X}h.01"}
        return any(kind in covering or kind.startswith("restore defaults") for kind in counts)

    def stored_to_give_back(self, stored: ReferencePoint | None, may_have_changed: bool) -> ReferencePoint | None:
        """The stored reference point to preset again (the device shows what it stored now), or None."""
        if stored is None or not may_have_changed:
            return None
        now = self.read()
        return stored if now is None or self.differs(now, stored) else None

    def differs(self, now: ReferencePoint, wanted: ReferencePoint) -> bool:
        """Whether ``now`` is another reference point than ``wanted`` (the offset modulo the range)."""
        if wanted.offset is None or now.offset is None or self.access is None:
            return now.position != wanted.position
        if now.offset == wanted.offset:
            return False
        return not same_offset(now.offset, wanted.offset, self.access.settings(functions=False).span)

    def give_back(self, target: ReferencePoint, settle: bool) -> Outcome:
        """Preset to ``target``; refusals are reported, not raised."""
        if self.access is None:
            return Outcome()
        try:
            return give_back_reference_point(self.access, target, settle)
        except SdoAbortedError as exc:
            return Outcome(problem=f"reference point ({target.describe()}) not given back: "
                                   f"{abort_name(exc.code)}")

    def store_keys(self) -> list[Key]:
        """The entries whose store command keeps a preset (the preset object)."""
        key = self.preset_key
        return [] if key is None else [key]

    def check(self, wanted: ReferencePoint, what: str) -> str | None:
        """None, or what is wrong with the reference point now (``what``: which one, e.g. 'stored')."""
        now = self.read()
        if now is None:
            return f"{what} reference point unreadable ({wanted.describe()} wanted)"
        if self.differs(now, wanted):
            return f"{what} reference point not restored: {now.describe()} instead of {wanted.describe()}"
        return None

