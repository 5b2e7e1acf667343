"""Work-area channel 1 of a device as the work-area suite sees it (CiA 406 6400h..6402h): limits written keeping
low <= high, the position put by preset, and the area state compared with the reference model
(``models.encoder.work_area``); a difference at a limit breaks only our inference."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from encoder_conformance.dut.bench import EncoderBench
from encoder_conformance.models.encoder import objects as od
from encoder_conformance.models.encoder.reference import EncoderReference
from encoder_conformance.plugin.evidence import Evidence

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
