"""Open readings: every point where CiA or a manual allows more than one behaviour, as data.

Each :class:`OpenReading` names the question, the sentence it comes from (document, version and
section a vendor can look up, or the manual's section), the readings the suites accept, and the
conformant **variant** of the twin that plays the reading our default twin does not. The variant
matrix (``tests/test_variant_matrix.py``) runs the suite modules each point concerns against every
variant, on every representative profile where it applies: a conformant reading must never fail.

One module per area holds its points (``sdo``, ``lss``, ``pdo``, ``errors``, ``nmt``); this module only
gathers them. Data only: the plugin, the command line and the simulator import it without each other.
"""

from __future__ import annotations

from encoder_conformance.open_points import errors, lss, nmt, pdo, sdo
from encoder_conformance.open_points.record import OpenReading

__all__ = ["OpenReading", "all_readings", "variant_modules", "variants"]


def all_readings() -> list[OpenReading]:
    """Every open point, in area order."""
    return [*sdo.READINGS, *lss.READINGS, *pdo.READINGS, *errors.READINGS, *nmt.READINGS]


def variants() -> dict[str, str]:
    """variant name -> its one-line description (what ``--sim-fault`` takes besides the faults)."""
    found: dict[str, str] = {}
    for reading in all_readings():
        if reading.variant in found:
            raise ValueError(f"variant {reading.variant!r} is declared by two open readings")
        found[reading.variant] = reading.variant_text
    return found


def variant_modules() -> dict[str, tuple[str, ...]]:
    """variant name -> the suite modules the variant matrix runs it against."""
    return {reading.variant: reading.modules for reading in all_readings()}
