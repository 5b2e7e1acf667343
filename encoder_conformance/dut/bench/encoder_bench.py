"""What an encoder test works with: typed access, a position mover, the reference model, and the put-back.

Every encoder test changes settings (scaling, code sequence, CAM, work area) through the journal and presets the
position: afterwards the settings are written back first (the offset means something only in their units), then
the shaft (where the bench turned it) goes back where it was, then the reference point is restored by presetting.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from encoder_conformance.dut.bench.encoder_access import EncoderAccess
from encoder_conformance.dut.bench.position_mover import PositionMover, PresetMover, ShaftMover
from encoder_conformance.dut.bench.reference_point import ReferencePoint, restore_reference_point
from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.models.encoder.reference import EncoderReference

SHOWN_CHANGES = 12  # changes named in the note after the test; the rest counted


@dataclass
class EncoderBench:
    """The encoder function of the device, its settings changed through the journal (put back after the test)."""

    access: EncoderAccess
    journal: SettingsJournal  # writes remembered and put back
    found: ReferencePoint
    shaft: ShaftMover | None
    why_no_shaft: str
    changed: list[str] = field(default_factory=list)

    @property
    def mover(self) -> PositionMover:
        """The shaft where the bench can turn it, else the preset."""
        return self.shaft if self.shaft is not None else PresetMover(self.access)

    def write(self, index: int, sub: int, value: int) -> None:
        """Write a setting (typed with the profile); put back after the test."""
        self.journal.remember(index, sub)
        self.access.write_int(index, sub, value)
        self.changed.append(f"{index:04X}h.{sub:02X} = {value}")

    def preset(self, value: int) -> int:
        """Preset the position; returns the position read afterwards (once it settled, where it lags)."""
        self.access.preset(value)
        self.changed.append(f"preset {value}")
        return self.access.position()

    def reference(self) -> EncoderReference:
        """The reference model with the device's settings as they are now."""
        return self.access.reference()

    def put_back(self) -> list[str]:
        """Settings, then the shaft, then the reference point (by presetting, where the device has a preset); what
        could not be put back."""
        problems = self.journal.restore()
        if self.shaft is not None:
            self.shaft.go_home()
        if self.access.dut.profile.capabilities.preset:
            problem = restore_reference_point(self.access, self.found)
            if problem:
                problems.append(problem)
        return problems

    def describe_changes(self) -> str | None:
        """What the test changed and the put-back undid, for the evidence; None where it changed nothing."""
        if not self.changed:
            return None
        more = len(self.changed) - SHOWN_CHANGES
        return ("changed and put back: " + "; ".join(self.changed[:SHOWN_CHANGES])
                + (f" (+{more} more)" if more > 0 else ""))
