"""Twin faults that only keep a check in scope from judging (``coverage.Hold``): no test can fail on them, so they
stay out of the fault matrix; the false-PASS matrix (``runs/false_pass_matrix.py``) runs each and sees the run end
INCOMPLETE, never PASS. Data only, as ``fault_catalogue``, which lists them among the simulator's deviations."""

from __future__ import annotations

from typing import NamedTuple


class HoldFault(NamedTuple):
    """What the twin does, and the suite modules it is made for."""

    text: str
    modules: tuple[str, ...]


HOLD_FAULTS: dict[str, HoldFault] = {
    "mapped_values_change_every_read": HoldFault(
        "an SDO read of a PDO-mappable integer entry shows its value plus the SYNCs since the last (re)start (the "
        "mapped objects change between every read before a SYNC and one after it; a TPDO carries the value)",
        ("test_pdo_mapping",)),
}
