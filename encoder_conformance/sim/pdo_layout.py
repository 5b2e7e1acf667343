"""Fixed TPDO layouts of devices without mapping objects (quirk effect ``fixed_tpdo_mapping``).

Example (FRABA POSITAL): 1800h and 1802h both carry 2000h (32 bits); 1800h is sent every
2200h ms whatever its sub 2 says and answers an RTR; 1802h is sent on every n-th SYNC,
n = 1802h sub 2 (1..255).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

Mapping = list[tuple[int, int, int]]  # (index, sub, bits)


def _specs(value: Any) -> list[dict[str, Any]]:
    """A params entry given as one mapping or a list of them."""
    if not value:
        return []
    return [value] if isinstance(value, dict) else list(value)


@dataclass(frozen=True)
class FixedTpdoLayout:
    mapping: dict[int, Mapping]  # comm index -> fixed mapping
    cyclic: dict[int, tuple[int, float]]  # comm index -> (period object, unit in ms)
    sync_counter: dict[int, int]  # comm index -> sub-index holding n (every n-th SYNC)
    polled: frozenset[int]  # comm indices answering an RTR

    @classmethod
    def from_params(cls, params: dict[str, Any]) -> FixedTpdoLayout:
        mapping = {
            int(comm): [(int(index), int(sub), int(bits)) for index, sub, bits in entries]
            for comm, entries in (params.get("mapping") or {}).items()
        }
        cyclic = {int(s["tpdo"]): (int(s["period_object"]), float(s.get("period_unit_ms", 1)))
                  for s in _specs(params.get("cyclic"))}
        sync = {int(s["tpdo"]): int(s.get("counter_subindex", 2)) for s in _specs(params.get("sync"))}
        polled = frozenset(int(s["tpdo"]) for s in _specs(params.get("polled")))
        return cls(mapping, cyclic, sync, polled)

    @property
    def timer_objects(self) -> frozenset[int]:
        """Objects whose write changes a TPDO's timing (the engine reloads on them)."""
        return frozenset(obj for obj, _ in self.cyclic.values())
