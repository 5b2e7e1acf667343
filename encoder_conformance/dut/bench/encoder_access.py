"""The encoder function of the device under test over SDO: its settings, position and offset, typed.

Values are decoded with the profile's data type of each entry (SIGNED types negative), so the
settings read here are the same inputs the reference model gets from the twin's object store
(``models.encoder.settings.read_settings``).
"""

from __future__ import annotations

from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.models.encoder import objects as od
from encoder_conformance.models.encoder.freeze import FreezeRule
from encoder_conformance.models.encoder.reference import EncoderReference
from encoder_conformance.models.encoder.settings import EncoderDescription, EncoderSettings, read_settings
from encoder_conformance.profile import datatypes
from encoder_conformance.profile import quirk_effects as fx


class EncoderAccess:
    """Typed reads and writes of the encoder objects of one device."""

    def __init__(self, dut: DeviceLink) -> None:
        self.dut = dut
        self.description = EncoderDescription.of(dut.profile)
        self.objects = self.description.objects
        self.freeze = FreezeRule.of(dut.profile)

    # -- typed entries ---------------------------------------------------------------------------
    def _type(self, index: int, sub: int) -> str | None:
        entry = self.dut.profile.entry(index, sub)
        return None if entry is None else entry.type

    def read_int(self, index: int, sub: int = 0) -> int | None:
        """The entry decoded with its profile data type; None where the profile does not declare it."""
        type_name = self._type(index, sub)
        if type_name is None:
            return None
        data = self.dut.read(index, sub)
        return int.from_bytes(data, "little", signed=datatypes.is_signed(type_name))

    def encode(self, index: int, sub: int, value: int) -> bytes:
        """``value`` as the entry's data type carries it (two's complement for SIGNED types)."""
        type_name = self._type(index, sub)
        if type_name is None:
            raise KeyError(f"{index:04X}h.{sub:02X} is not in profile {self.dut.profile.id}")
        size = datatypes.size_bytes(type_name) or 4
        return (value % (1 << 8 * size)).to_bytes(size, "little")

    def write_int(self, index: int, sub: int, value: int) -> None:
        self.dut.write(index, sub, self.encode(index, sub, value))

    def wait_until_executed(self) -> None:
        """Wait out the execution time the manual gives for the writes made so far (its position is frozen
        meanwhile)."""
        self.dut.wait_until_executed()

    # -- the encoder function -----------------------------------------------------------------------
    def settings(self, offset: int | None = None, functions: bool = True) -> EncoderSettings:
        """Everything the position, CAM and work-area values depend on, as the device shows it now
        (``functions=False``: only what the position depends on, a few reads instead of dozens)."""
        return read_settings(self.description, self.read_int, offset, functions)

    def reference(self) -> EncoderReference:
        """A reference model with the device's current settings (no CAM history)."""
        return EncoderReference(self.settings(), self.description.cam_rules)

    @property
    def has_offset_object(self) -> bool:
        """The device shows CiA 406's offset (6509h = preset - position before it); not where a quirk
        says its 6509h means something else (``offset_is_zeroing_point``)."""
        profile = self.dut.profile
        return (not self.objects.relocated and profile.entry(od.OFFSET, 0) is not None
                and not profile.has_effect(fx.OffsetIsZeroingPoint))

    def offset(self) -> int | None:
        """6509h, where the device has it with CiA 406's meaning."""
        return self.read_int(od.OFFSET, 0) if self.has_offset_object else None

    def position(self) -> int:
        """The position value read by SDO (limit-switch flag bits removed where the profile declares them),
        once the device executed the writes before it."""
        self.wait_until_executed()
        value = self.read_int(self.objects.position, 0)
        assert value is not None, f"{self.objects.position:04X}h (position) is not in the profile"
        flags = self.description.flags
        if flags is not None and self.objects.position == flags.value_object and "sdo" in flags.channels:
            value &= flags.position_mask
        return value

    def preset(self, value: int) -> None:
        """Write the preset object (6003h, or the manufacturer's). Where the device takes a preset only with
        the scaling bit set (quirk ``writes_need_scaling_bit``), the bit is set for the write and put back."""
        bit = self.scaling_bit_needed_for_preset()
        if bit is None:
            self.write_int(self.objects.preset, 0, value)
            return
        operating = self.read_int(self.objects.operating, 0) or 0
        self.write_int(self.objects.operating, 0, operating | bit)
        try:
            self.write_int(self.objects.preset, 0, value)
        finally:
            self.write_int(self.objects.operating, 0, operating)

    def scaling_bit_needed_for_preset(self) -> int | None:
        """The scaling bit mask where it is clear now and the preset needs it, else None."""
        found = self.dut.profile.params_of(fx.WritesNeedScalingBit)
        if found is None or self.objects.preset not in found.indices or self.objects.scaling_bit is None:
            return None
        bit = 1 << self.objects.scaling_bit
        return None if (self.read_int(self.objects.operating, 0) or 0) & bit else bit

    def position_when(self, wanted: int, timeout: float = 0.0) -> int:
        """The position once the device executed its writes, read again until it equals ``wanted`` or
        ``timeout`` is over (returns the last read)."""
        deadline = Deadline(timeout)
        while True:
            value = self.position()
            if value == wanted or deadline.expired():
                return value
