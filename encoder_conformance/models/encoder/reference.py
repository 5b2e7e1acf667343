"""The executable reference of one encoder: what it must show for a shaft angle and its settings.

``EncoderReference`` keeps what the values depend on besides the settings: the CAM history (for
hysteresis). The twin computes its values with it; the suites ask it what a device must show
after the same settings and moves. Pure: no I/O, no clock.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import encoder_conformance.models.encoder.position as pos
from encoder_conformance.models.encoder.cam import CamRules, CamTracker
from encoder_conformance.models.encoder.settings import EncoderSettings
from encoder_conformance.models.encoder.speed import speed_value
from encoder_conformance.models.encoder.work_area import area_state


@dataclass
class EncoderReference:
    """Position, preset, CAM, work area and speed of one encoder, given its settings."""

    settings: EncoderSettings
    cam_rules: CamRules = field(default_factory=CamRules)
    trackers: list[CamTracker] = field(default_factory=list)

    # -- position ----------------------------------------------------------------------------
    def unsigned_position(self, turns: float) -> int:
        return pos.position_value(turns, self.settings.geometry, self.settings.scaling)

    def position(self, turns: float) -> int:
        """The position value as the device shows it (signed where the device is signed)."""
        return self.settings.shown(self.unsigned_position(turns))

    def offset_for_preset(self, preset: int, turns: float) -> int:
        """The offset (6509h) writing ``preset`` at shaft angle ``turns`` must produce."""
        unshifted = pos.unshifted_position(turns, self.settings.geometry, self.settings.scaling)
        return pos.preset_offset(preset, unshifted, self.settings.span)

    def apply_preset(self, preset: int, turns: float) -> int:
        """Take the offset a preset produces into the settings; returns that offset."""
        offset = self.offset_for_preset(preset, turns)
        self.settings = replace(self.settings, scaling=replace(self.settings.scaling, offset=offset))
        return offset

    def shown_offset(self) -> int:
        """The offset as 6509h (SIGNED32) shows it: the part of the range above half is negative."""
        return self.settings.shown(self.settings.scaling.offset) if self.settings.signed else \
            self.settings.scaling.offset

    def turns_for(self, target: int) -> float | None:
        """A shaft angle at which the position reads ``target`` (None if scaling skips that value)."""
        counts = pos.counts_for_position(pos.unsigned_in_span(target, self.settings.span), self.settings.geometry,
                                         self.settings.scaling)
        return None if counts is None else pos.turns_for_counts(counts, self.settings.geometry)

    # -- CAM, work area, speed ---------------------------------------------------------------
    def cam_state(self, position: int, channel: int = 1) -> int:
        """6300h sub ``channel`` after the position reached ``position`` (updates the hysteresis history)."""
        channels = self.settings.cam_channels
        while len(self.trackers) < len(channels):
            self.trackers.append(CamTracker(self.cam_rules))
        return self.trackers[channel - 1].update(position, channels[channel - 1])

    def forget_cam_history(self) -> None:
        for tracker in self.trackers:
            tracker.forget()

    def area_state(self, position: int, channel: int = 1) -> int:
        low, high = self.settings.areas[channel - 1]
        return area_state(position, low, high)

    def speed(self, revolutions_per_second: float) -> int:
        units = pos.units_per_rev(self.settings.geometry, self.settings.scaling)
        return speed_value(revolutions_per_second, units, self.settings.scaling.ccw, self.settings.speed_factor)
