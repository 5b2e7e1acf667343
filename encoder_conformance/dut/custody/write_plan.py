"""The order in which a set of values can be written back to a device (CiA 301 procedures, profile quirks).

Writing values back is not a loop over the entries: a PDO must be made invalid (COB-ID bit 31)
before its parameters change and its mapping count set to 0 before its mapping entries change
(CiA 301 §7.5.2.35-§7.5.2.38); a device may refuse writes until another value opens a gate
(quirk ``writes_need_scaling_bit``). The plan adds these temporary steps.
"""

from __future__ import annotations

from dataclasses import dataclass

from encoder_conformance.cia.cia301 import (
    COB_ID_INVALID,
    PDO_MAPPING_OFFSET,
    RPDO_COMMUNICATION,
    TPDO_COMMUNICATION,
    pdo_mapping_of,
)
from encoder_conformance.profile.quirk_effects import WritesNeedScalingBit
from encoder_conformance.profile.schema import DeviceProfile

Key = tuple[int, int]
SCALING_GATE = (0x6000, 0)  # CiA 406 operating parameters; bit 2 = scaling function control
SCALING_BIT = 0x04


@dataclass(frozen=True)
class Step:
    key: Key
    value: bytes
    temporary: bool = False  # a procedure step, overwritten later in the plan

    @property
    def label(self) -> str:
        return f"{self.key[0]:04X}h.{self.key[1]:02X} = {self.value.hex(' ').upper()}"


def _as_int(data: bytes | None) -> int | None:
    return None if data is None else int.from_bytes(data, "little")


def _with_bits(data: bytes, bits: int) -> bytes:
    return (int.from_bytes(data, "little") | bits).to_bytes(len(data), "little")


def _writable(profile: DeviceProfile, key: Key) -> bool:
    entry = profile.entry(*key)
    return entry is not None and entry.writable


def _pdo_steps(profile: DeviceProfile, comm: int, remaining: dict[Key, bytes], current: dict[Key, bytes | None]
               ) -> list[Step]:
    """Invalidate, write parameters and mapping (count 0 first), then the target COB-ID."""
    steps: list[Step] = []
    cob_key = (comm, 1)
    cob_now = current.get(cob_key)
    cob_target = remaining.pop(cob_key, cob_now)
    invalidate = (_writable(profile, cob_key) and cob_now is not None
                  and not (_as_int(cob_now) or 0) & COB_ID_INVALID)
    if invalidate and cob_now is not None:  # invalidate implies cob_now
        steps.append(Step(cob_key, _with_bits(cob_now, COB_ID_INVALID), temporary=True))
    steps += [Step(k, remaining.pop(k)) for k in sorted(k for k in remaining if k[0] == comm)]
    mapping = pdo_mapping_of(comm)
    assert mapping is not None  # comm is a PDO communication index (_pdo_communication_indices)
    mapped = sorted(k for k in remaining if k[0] == mapping and k[1] > 0)
    count_key = (mapping, 0)
    count_target = remaining.pop(count_key, current.get(count_key))
    if mapped and _writable(profile, count_key) and count_target is not None:
        steps.append(Step(count_key, bytes(len(count_target)), temporary=True))
        steps += [Step(k, remaining.pop(k)) for k in mapped]
        steps.append(Step(count_key, count_target))
    else:
        steps += [Step(k, remaining.pop(k)) for k in mapped]
        if count_target is not None and count_target != current.get(count_key):
            steps.append(Step(count_key, count_target))
    if cob_target is not None and (invalidate or cob_target != cob_now):
        steps.append(Step(cob_key, cob_target))
    return steps


def _pdo_communication_indices(keys: list[Key]) -> list[int]:
    comms = set()
    for index, _ in keys:
        if index in TPDO_COMMUNICATION or index in RPDO_COMMUNICATION:
            comms.add(index)
        elif index - PDO_MAPPING_OFFSET in TPDO_COMMUNICATION or index - PDO_MAPPING_OFFSET in RPDO_COMMUNICATION:
            comms.add(index - PDO_MAPPING_OFFSET)
    return sorted(comms)


def _gated_steps(profile: DeviceProfile, remaining: dict[Key, bytes], current: dict[Key, bytes | None]
                 ) -> list[Step]:
    """Writes a device refuses unless 6000h bit 2 is set: set it, write them, then 6000h's own value."""
    found = profile.params_of(WritesNeedScalingBit)
    if found is None:
        return []
    gated_indices = found.indices
    gated = sorted(k for k in remaining if k[0] in gated_indices)
    gate_now = current.get(SCALING_GATE)
    if not gated or gate_now is None:
        return []
    gate_target = remaining.pop(SCALING_GATE, gate_now)
    steps = []
    if not (_as_int(gate_now) or 0) & SCALING_BIT:
        steps.append(Step(SCALING_GATE, _with_bits(gate_now, SCALING_BIT), temporary=True))
    steps += [Step(k, remaining.pop(k)) for k in gated]
    if steps[0].temporary or gate_target != gate_now:
        steps.append(Step(SCALING_GATE, gate_target))
    return steps


def plan_writes(profile: DeviceProfile, targets: dict[Key, bytes], current: dict[Key, bytes | None]) -> list[Step]:
    """Steps that bring every key of ``targets`` to its value, starting from ``current``."""
    remaining = dict(targets)
    steps = _gated_steps(profile, remaining, current)
    for comm in _pdo_communication_indices(list(remaining)):
        steps += _pdo_steps(profile, comm, remaining, current)
    steps += [Step(k, remaining[k]) for k in sorted(remaining)]
    return steps
