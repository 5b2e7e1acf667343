"""Faults a check in scope cannot judge (``coverage.Hold``): against one of them the run must end INCOMPLETE, never
PASS and never FAIL. Data only, as ``fault_catalogue``; they stay out of the fault matrix (no test can fail on them):
``tests/test_hold_faults.py`` runs each against its target modules."""

from __future__ import annotations

from typing import NamedTuple


class HoldFault(NamedTuple):
    """What the twin does, the suite modules it is made for, the hold (``coverage.Hold`` name) they must name."""

    text: str
    modules: tuple[str, ...]
    hold: str


HOLD_FAULTS: dict[str, HoldFault] = {
    "mapped_values_change_every_read": HoldFault(
        "an SDO read of a PDO-mappable integer entry shows its value plus the SYNCs since the last (re)start (the "
        "mapped objects change between every read before a SYNC and one after it; a TPDO carries the value)",
        ("test_pdo_mapping",), "VALUES_CHANGED"),
}
