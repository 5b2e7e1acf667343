"""How long a device's position stays frozen after a write it executes (quirk ``position_frozen_during_execution``).

The device answers the SDO write first and executes it afterwards, showing the old position
meanwhile (SIKO: about 40-160 ms per object, M §5.2). The twin freezes its position for that long;
the DUT layer waits that long before it trusts a position read (what the device owes, from its
manual, not a guess).
"""

from __future__ import annotations

from dataclasses import dataclass

from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile

SCALING_BIT_SET = 0x04  # 6000h bit 2: the manual gives the scaling switch its own duration


@dataclass(frozen=True)
class FreezeRule:
    objects: frozenset[int]
    duration_ms: float
    durations_ms: dict[str, float]

    @classmethod
    def from_params(cls, params: fx.PositionFrozenDuringExecution) -> FreezeRule:
        durations = {k.lower(): v for k, v in params.durations_ms.items()}
        return cls(params.indices, params.duration_ms, durations)

    @classmethod
    def of(cls, profile: DeviceProfile) -> FreezeRule | None:
        params = profile.params_of(fx.PositionFrozenDuringExecution)
        return None if params is None else cls.from_params(params)

    def duration_s(self, index: int, value: object) -> float:
        """0 when a write to ``index`` does not freeze the position."""
        if index not in self.objects:
            return 0.0
        name = f"0x{index:04x}"
        if isinstance(value, int) and value & SCALING_BIT_SET and f"{name}.scaling_bit_set" in self.durations_ms:
            return self.durations_ms[f"{name}.scaling_bit_set"] / 1000
        return self.durations_ms.get(name, self.duration_ms) / 1000
