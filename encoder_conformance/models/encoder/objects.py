"""Where each CiA 406 role lives on a device: 6000h..6004h, or the manufacturer objects a profile names."""

from __future__ import annotations

from dataclasses import dataclass

from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile

#: CiA 406 CAM and work-area objects (channel n at sub-index n)
CAM_STATE, CAM_ENABLE, CAM_POLARITY = 0x6300, 0x6301, 0x6302
CAM_LOW, CAM_HIGH, CAM_HYSTERESIS = 0x6310, 0x6320, 0x6330
AREA_STATE, AREA_LOW, AREA_HIGH = 0x6400, 0x6401, 0x6402
SPEED = 0x6030
OFFSET = 0x6509
HIGH_PRECISION_PRESET = 0x6009  # C3: the preset as 64 bits; writing it presets like 6003h
OPERATING_STATUS = 0x6500
MODULE_IDENTIFICATION = 0x650A
SINGLE_TURN_RESOLUTION = 0x6501
REVOLUTIONS = 0x6502
CODE_SEQUENCE_BIT = 0


def cam_limit_objects(cam: int) -> tuple[int, int, int]:
    """(low, high, hysteresis) object of cam ``cam`` (0-based: CAM1 is 0)."""
    return CAM_LOW + cam, CAM_HIGH + cam, CAM_HYSTERESIS + cam


@dataclass(frozen=True)
class EncoderObjects:
    """Where the CiA 406 roles live on this device (quirk effect ``manufacturer_encoder_objects``)."""

    operating: int = 0x6000
    units_per_rev: int = 0x6001
    total_range: int = 0x6002
    preset: int = 0x6003
    position: int = 0x6004
    scaling_bit: int | None = 2  # None: the scaling objects always apply

    @property
    def relocated(self) -> bool:
        """True where the function lives in manufacturer objects (no 6501h/6502h/6509h to read)."""
        return self.position != 0x6004

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
