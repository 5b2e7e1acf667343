"""Work area (CiA 406 6400h..6402h): the area state from the position and the work-area limits of channel 1.

The limits are written so that low <= high at every moment, the position is put where each check needs
it by presetting (no rotation needed), and 6400h sub 1 is compared with the reference model
(``models.encoder.work_area``) fed with the limits read back from the device. The state values (00h
inside, 02h above the high limit, 04h below the low limit) rest on CiA 406 6400h and WDGA T 6.9;
that the limits themselves belong to the work area is our inference (no text we know says so).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import pytest

from encoder_conformance.models.encoder import objects as od
from encoder_conformance.models.encoder.reference import EncoderReference
from encoder_conformance.plugin.evidence import Evidence
from fixtures.encoder import EncoderBench

# the position is put by preset (capability preset), so the tests run on a bench without a motor
pytestmark = [pytest.mark.spec("CiA 406 6400h-6402h (work area)"), pytest.mark.requires("work_area", "preset"),
              pytest.mark.destructive]

CHANNEL = 1  # the model and the tests cover work-area channel 1
AREA_RULE = "CiA 406 6400h-6402h (area state: bit 1 above the high limit, bit 2 below the low limit); WDGA T 6.9"
EDGE_RULE = "the work-area limits belong to the work area (CiA 406 and WDGA M §11.6 leave the edges open)"
ROOM = 1 << 16  # the limits lie within this many units (readable positions on any range)
NAMES = {0x00: "inside", 0x02: "above", 0x04: "below"}


def _describe(state: int) -> str:
    return f"{state:02X}h ({NAMES.get(state, 'other')})"


@dataclass
class WorkArea:
    """Work-area channel 1 of the device: limits written keeping low <= high, the position put by preset."""

    encoder: EncoderBench
    span: int
    lowest: int  # the smallest position value
    problems: list[str] = field(default_factory=list)
    steps: int = 0

    @property
    def room(self) -> int:
        """How many units from the smallest position the tests use (within half the range: valid on signed
        devices too)."""
        return min(self.span // 2, ROOM)

    def _read(self, index: int) -> int:
        value = self.encoder.access.read_int(index, CHANNEL)
        assert value is not None, f"{index:04X}h.{CHANNEL:02X} is not in the profile"
        return value

    def set_limits(self, reference: EncoderReference | None, low: int, high: int) -> EncoderReference:
        """Write 6401h/6402h in the order that keeps low <= high (high first when the area moves up); the
        reference model with the limits read back (checked against those written)."""
        current_high = self._read(od.AREA_HIGH)
        order = ((od.AREA_HIGH, high), (od.AREA_LOW, low)) if low > current_high else \
            ((od.AREA_LOW, low), (od.AREA_HIGH, high))
        for index, value in order:
            self.encoder.write(index, CHANNEL, value)
        if reference is None:
            reference = self.encoder.reference()
        else:
            areas = list(reference.settings.areas)
            areas[CHANNEL - 1] = (self._read(od.AREA_LOW), self._read(od.AREA_HIGH))
            reference.settings = replace(reference.settings, areas=tuple(areas))
        read_back = reference.settings.areas[CHANNEL - 1]
        assert read_back == (low, high), f"work-area limits 6401h/6402h read {read_back}, written ({low}, {high})"
        return reference

    def move(self, position: int) -> None:
        """Put the position at ``position`` by presetting."""
        reached = self.encoder.preset(position)
        assert reached == position, (f"preset {position}: the position reads {reached} (see the preset tests); "
                                     "the work-area checks need the position where they put it")

    def check(self, reference: EncoderReference, what: str, position: int, evidence: Evidence,
              edge: bool = False) -> None:
        """6400h at ``position`` against the model; at a limit (``edge``) a difference breaks only our inference."""
        observed = self._read(od.AREA_STATE)
        expected = reference.area_state(position, CHANNEL)
        self.steps += 1
        if observed == expected:
            return
        low, high = reference.settings.areas[CHANNEL - 1]
        text = (f"{what}: position {position}, limits [{low}, {high}]: 6400h.{CHANNEL:02X} = {_describe(observed)}, "
                f"expected {_describe(expected)}")
        if edge:
            evidence.inferred_problem(text, EDGE_RULE)
        else:
            self.problems.append(text)

    def report(self, evidence: Evidence) -> None:
        evidence.rests_on("cia", AREA_RULE)
        evidence.note(f"{self.steps} area states compared with the reference model")
        if self.problems:
            raise AssertionError("area state differs from the reference model:\n" + "\n".join(self.problems))


@pytest.fixture
def work_area(encoder: EncoderBench) -> WorkArea:
    """Work-area channel 1 (limits put back after the test by the encoder fixture)."""
    settings = encoder.access.settings()
    if settings.span < 64:
        pytest.skip(f"not applicable: a position range of {settings.span} is too small for the work-area layout")
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
