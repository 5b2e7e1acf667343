"""Which TPDO a transmission test may use: mapped, configurable where the test needs it, not fixed by a quirk.

Shared by the TPDO suites and the periodic capture (heartbeat and event timer measured together), so
both pick the same TPDO for the same reasons.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from encoder_conformance.cia.cia301 import COB_ID_INVALID, PDO_MAPPING_OFFSET, cob_id_valid
from encoder_conformance.coverage import Hold
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.errors import NoUsableTpdo
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import resolve_node_id_expression
from encoder_conformance.profile.value_domain import declared_domain


@dataclass
class TpdoChoice:
    """The TPDO to use, what to write before the test, and what the report should say about the choice."""

    comm: int
    transmission_type: int
    enable_cob_id: int | None = None  # sub 1 value that clears bit 31, where the TPDO is disabled
    notes: list[str] = field(default_factory=list)
    deviations: list[tuple[str, str]] = field(default_factory=list)  # (quirk id, text)


def fixed_behaviour_tpdos(dut: DeviceLink) -> tuple[set[int], tuple[str, str] | None]:
    """TPDOs whose behaviour a fixed-layout quirk decides (e.g. POSITAL 1800h: cyclic by 2200h, sub 2
    ignored), and the deviation to report for skipping them."""
    found = dut.profile.quirk(fx.FixedTpdoMapping)
    if found is None:
        return set(), None
    specs: list[fx.CyclicTpdo | fx.PolledTpdo] = [*found.params.cyclic_tpdos, *found.params.polled_tpdos]
    fixed = {spec.tpdo for spec in specs}
    if not fixed:
        return set(), None
    return fixed, (found.id, f"{found.quirk.title}: {', '.join(f'{c:04X}h' for c in sorted(fixed))} not used here")


def choose_tpdo(dut: DeviceLink, sub: int, usable_types: list[int],
                leave_alone: frozenset[tuple[int, int]] = frozenset()) -> TpdoChoice:
    """The first TPDO that maps something, whose sub-index ``sub`` is writable and whose type is one of
    ``usable_types`` (in order of preference): to be written if sub 2 is writable, else as the device has
    it fixed. A disabled TPDO (sub 1 bit 31) is chosen only if sub 1 is writable (``enable_cob_id``);
    none whose sub-index ``sub`` is in ``leave_alone``.

    Raises NoUsableTpdo when none qualifies.
    """
    fixed, deviation = fixed_behaviour_tpdos(dut)
    configured_away: list[str] = []  # TPDOs the profile makes usable that the device's configuration leaves out
    for comm in sorted(i for i in dut.profile.objects if 0x1800 <= i <= 0x19FF and i not in fixed):
        entry, kind, cob = (dut.profile.entry(comm, s) for s in (sub, 2, 1))
        if entry is None or kind is None or cob is None or not entry.writable or (comm, sub) in leave_alone:
            continue
        mapping = comm + PDO_MAPPING_OFFSET
        count = dut.profile.entry(mapping, 0)
        if count is not None and dut.read_uint(mapping, 0) == 0:
            if isinstance(count.default, int) and count.default:  # mapped by default: configured otherwise here
                configured_away.append(f"{mapping:04X}h.00 = 0 (default {count.default})")
            continue  # nothing mapped
        accepted = declared_domain(dut.profile, comm, 2)  # the profile's types within the entry's own limits
        candidates = ([t for t in usable_types if accepted is None or t in accepted] if kind.writable
                      else [dut.read_uint(comm, 2)])
        chosen = next((t for t in candidates if t in usable_types), None)
        cob_id = dut.read_uint(comm, 1)
        if chosen is None or (cob_id & COB_ID_INVALID and not cob.writable):
            default = resolve_node_id_expression(cob.default, dut.node_id)
            if chosen is not None and isinstance(default, int) and not default & COB_ID_INVALID:
                configured_away.append(f"{comm:04X}h.01 = {cob_id:08X}h (disabled, read-only; default valid)")
            continue
        choice = TpdoChoice(comm, chosen, deviations=[deviation] if deviation else [])
        if cob_id & COB_ID_INVALID:
            choice.enable_cob_id = cob_id_valid(cob_id)
            choice.notes.append(f"{comm:04X}h.01 bit 31 cleared (TPDO enabled) for the test")
        if not kind.writable:
            choice.notes.append(f"{comm:04X}h.02 is read-only: its fixed type {chosen} is used")
        return choice
    deviations = [deviation] if deviation else []
    if configured_away:
        raise NoUsableTpdo(f"not testable: no TPDO with writable sub-index {sub} is usable as the device is "
                           f"configured: {'; '.join(configured_away)}", deviations, Hold.NO_USABLE_TPDO)
    raise NoUsableTpdo(f"not applicable: no mapped TPDO with writable sub-index {sub} and a usable transmission type",
                       deviations)
