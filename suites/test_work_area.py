"""Work area (CiA 406 6400h..6402h): the area state from the position and the work-area limits of channel 1.

The limits are written so that low <= high at every moment, the position is put where each check needs
it by presetting (no rotation needed), and 6400h sub 1 is compared with the reference model
(``models.encoder.work_area``) fed with the limits read back from the device. The state values (00h
inside, 02h above the high limit, 04h below the low limit) rest on CiA 406 6400h and WDGA T 6.9;
that the limits themselves belong to the work area is our inference (no text we know says so).
"""

from __future__ import annotations

import pytest

from encoder_conformance.dut.bench import EncoderBench
from encoder_conformance.plugin.evidence import Evidence
from encoder_conformance.plugin.skips import not_applicable
from encoder_conformance.plugin.suite_helpers import WorkArea

# the position is put by preset (capability preset), so the tests run on a bench without a motor
pytestmark = [pytest.mark.spec("CiA 406 6400h-6402h (work area)"), pytest.mark.requires("work_area", "preset"),
              pytest.mark.destructive]


@pytest.fixture
def work_area(encoder: EncoderBench) -> WorkArea:
    """Work-area channel 1 (limits put back after the test by the encoder fixture)."""
    settings = encoder.access.settings()
    if settings.span < 64:
        not_applicable(f"a position range of {settings.span} is too small for the work-area layout")
    return WorkArea(encoder, settings.span, settings.limits()[0])


def test_area_state_below_inside_above(work_area: WorkArea, evidence: Evidence) -> None:
    """04h below the low limit, 00h inside, 02h above the high limit, at low-1, low, mid, high, high+1 and further
    out (CiA 406 6400h, WDGA T 6.9; the limits inside the area: inferred)."""
    pitch = work_area.room // 4
    low, high = work_area.lowest + pitch, work_area.lowest + 2 * pitch
    reference = work_area.set_limits(None, low, high)
    for label, position in (("far below", low - pitch // 2), ("low-1", low - 1), ("low", low),
                            ("middle", (low + high) // 2), ("high", high), ("high+1", high + 1),
                            ("far above", high + pitch // 2)):
        work_area.move(position)
        work_area.check(reference, label, position, evidence, edge=position in (low, high))
    work_area.report(evidence)


def test_area_state_follows_changed_limits(work_area: WorkArea, evidence: Evidence) -> None:
    """The position held still, the limits moved around it: the state follows the limits at once (inside, below
    the area, above it, inside again; CiA 406 6400h-6402h)."""
    pitch = work_area.room // 8
    position = work_area.lowest + 4 * pitch
    work_area.move(position)
    reference = None
    for label, (low, high) in (("area around the position", (position - pitch, position + pitch)),
                               ("area moved above the position", (position + pitch, position + 2 * pitch)),
                               ("area moved below the position", (position - 2 * pitch, position - pitch)),
                               ("area around the position again", (position - pitch, position + pitch))):
        reference = work_area.set_limits(reference, low, high)
        work_area.check(reference, label, position, evidence)
    work_area.report(evidence)
