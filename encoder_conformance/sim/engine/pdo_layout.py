"""Fixed TPDO layouts of devices without mapping objects (quirk effect ``fixed_tpdo_mapping``).

Example (FRABA POSITAL): 1800h and 1802h both carry 2000h (32 bits); 1800h is sent every
2200h ms whatever its sub 2 says and answers an RTR; 1802h is sent on every n-th SYNC,
n = 1802h sub 2 (1..255).
"""

from __future__ import annotations

from dataclasses import dataclass

from encoder_conformance.profile.quirk_effects import FixedTpdoMapping

Mapping = list[tuple[int, int, int]]  # (index, sub, bits)


@dataclass(frozen=True)
class FixedTpdoLayout:
    mapping: dict[int, Mapping]  # comm index -> fixed mapping
    cyclic: dict[int, tuple[int, float]]  # comm index -> (period object, unit in ms)
    sync_counter: dict[int, int]  # comm index -> sub-index holding n (every n-th SYNC)
    polled: frozenset[int]  # comm indices answering an RTR

    @classmethod
    def from_params(cls, params: FixedTpdoMapping) -> FixedTpdoLayout:
        mapping = {comm: list(entries) for comm, entries in params.mapping.items()}
        cyclic = {s.tpdo: (s.period_object, s.period_unit_ms) for s in params.cyclic_tpdos}
        sync = {s.tpdo: s.counter_subindex for s in params.sync_tpdos}
        polled = frozenset(s.tpdo for s in params.polled_tpdos)
        return cls(mapping, cyclic, sync, polled)

    @property
    def timer_objects(self) -> frozenset[int]:
        """Objects whose write changes a TPDO's timing (the engine reloads on them)."""
        return frozenset(obj for obj, _ in self.cyclic.values())
