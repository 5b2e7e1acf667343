"""CAM channel 1 of a device as the CAM suite sees it (CiA 406 6300h..6337h): settings written in the profile's
order, the position put by preset, and the differences between the device's 6300h and the reference model
(``models.encoder.cam``), sorted into failures and breaks of an inferred rule."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from encoder_conformance.basis import Basis
from encoder_conformance.dut.bench import EncoderBench
from encoder_conformance.dut.link import DeviceLink
from encoder_conformance.models.encoder import objects as od
from encoder_conformance.models.encoder.cam import Cam
from encoder_conformance.models.encoder.reference import EncoderReference
from encoder_conformance.plugin.evidence import Evidence
from encoder_conformance.plugin.skips import not_applicable

CHANNEL = 1  # the tests use CAM channel 1 (sub-index 1 of every CAM object)
WINDOW_RULE = "CiA 406 6300h-6302h, 6310h-6327h (CAM state, enable, polarity, limits)"
ROOM = 1 << 16  # the windows lie within this many units (readable positions on any range)


def cam_names(mask: int) -> str:
    """The cams whose bits ``mask`` sets: 'CAM1, CAM3'."""
    return ", ".join(f"CAM{n + 1}" for n in range(8) if mask >> n & 1) or "none"


@dataclass
class Findings:
    """Differences between the device's 6300h and the model: failures, and those that break only an inferred rule."""

    hard: list[str] = field(default_factory=list)
    inferred: list[tuple[str, str]] = field(default_factory=list)  # (observation, rule)
    steps: int = 0

    def compare(self, what: str, observed: int, expected: int, inferred: Mapping[int, str] | None = None) -> None:
        """``inferred``: cam number -> the inferred rule alone deciding that cam's bit at this step."""
        self.steps += 1
        diff = observed ^ expected
        if not diff:
            return
        inferred = inferred or {}
        text = f"{what}: 6300h.{CHANNEL:02X} = {observed:02X}h, expected {expected:02X}h"
        firm = [n for n in range(8) if diff >> n & 1 and n not in inferred]
        soft = [n for n in range(8) if diff >> n & 1 and n in inferred]
        if firm:
            self.hard.append(f"{text} (differs in {cam_names(sum(1 << n for n in firm))})")
        for n in soft:
            self.inferred.append((f"{text} (CAM{n + 1} differs)", inferred[n]))

    def report(self, evidence: Evidence, rests_on: tuple[Basis, str] = ("cia", WINDOW_RULE)) -> None:
        basis, source = rests_on
        evidence.rests_on(basis, source)
        evidence.note(f"{self.steps} CAM states compared with the reference model")
        for observation, rule in self.inferred:
            evidence.inferred_problem(observation, rule)
        if self.hard:
            raise AssertionError("CAM state differs from the reference model:\n" + "\n".join(self.hard))


@dataclass
class CamChannel:
    """CAM channel 1 of the device: settings written in the profile's order, the position put by preset."""

    encoder: EncoderBench
    count: int  # cams per channel
    high_first: bool  # quirk cam_low_below_high: a low limit is accepted only below the high limit
    span: int
    lowest: int  # the smallest position value

    @property
    def dut(self) -> DeviceLink:
        return self.encoder.access.dut

    # -- settings ------------------------------------------------------------------------------
    def configure(self, cams: Mapping[int, Cam], enable: int, polarity: int = 0) -> EncoderReference:
        """Write enable, polarity, hysteresis, high limits, then low limits (WDGA M §8.11 order); returns the
        reference model with the settings read back (checked against those written)."""
        write = self.encoder.write
        write(od.CAM_ENABLE, CHANNEL, enable)
        write(od.CAM_POLARITY, CHANNEL, polarity)
        for number, cam in cams.items():
            write(od.cam_limit_objects(number)[2], CHANNEL, cam.hysteresis)
        limits = (1, 0) if self.high_first else (0, 1)
        for which in limits:
            for number, cam in cams.items():
                write(od.cam_limit_objects(number)[which], CHANNEL, (cam.low, cam.high)[which])
        reference = self.encoder.reference()
        channel = reference.settings.cam_channels[CHANNEL - 1]
        wrong = [f"CAM{n + 1} {channel.cams[n]}, written {cam}" for n, cam in cams.items() if channel.cams[n] != cam]
        if (channel.enable, channel.polarity) != (enable, polarity):
            wrong.append(f"enable/polarity {channel.enable:02X}h/{channel.polarity:02X}h, written "
                         f"{enable:02X}h/{polarity:02X}h")
        assert not wrong, "CAM settings read back differ from those written: " + "; ".join(wrong)
        return reference

    def set_registers(self, reference: EncoderReference, enable: int | None = None,
                      polarity: int | None = None) -> None:
        """Write 6301h/6302h and take them, read back, into ``reference`` (its hysteresis history kept)."""
        channel = reference.settings.cam_channels[CHANNEL - 1]
        if enable is not None:
            self.encoder.write(od.CAM_ENABLE, CHANNEL, enable)
            channel = replace(channel, enable=self._read(od.CAM_ENABLE))
            assert channel.enable == enable, f"6301h.{CHANNEL:02X} reads {channel.enable:02X}h, written {enable:02X}h"
        if polarity is not None:
            self.encoder.write(od.CAM_POLARITY, CHANNEL, polarity)
            channel = replace(channel, polarity=self._read(od.CAM_POLARITY))
            assert channel.polarity == polarity, (f"6302h.{CHANNEL:02X} reads {channel.polarity:02X}h, "
                                                  f"written {polarity:02X}h")
        channels = list(reference.settings.cam_channels)
        channels[CHANNEL - 1] = channel
        reference.settings = replace(reference.settings, cam_channels=tuple(channels))

    def _read(self, index: int) -> int:
        value = self.encoder.access.read_int(index, CHANNEL)
        assert value is not None, f"{index:04X}h.{CHANNEL:02X} is not in the profile"
        return value

    # -- position and state --------------------------------------------------------------------
    def move(self, position: int) -> None:
        """Put the position at ``position`` by presetting (no rotation: a jump, as the CAM sees it)."""
        reached = self.encoder.preset(position)
        assert reached == position, (f"preset {position}: the position reads {reached} (see the preset tests); "
                                     "the CAM checks need the position where they put it")

    def state(self) -> int:
        return self._read(od.CAM_STATE)

    def visit(self, reference: EncoderReference, position: int) -> tuple[int, int]:
        """Move there; (observed, expected) 6300h, the model stepped to the same position."""
        self.move(position)
        return self.state(), reference.cam_state(position, CHANNEL)

    # -- windows -------------------------------------------------------------------------------
    def windows(self, hysteresis: int = 0) -> dict[int, Cam]:
        """Disjoint windows, one per cam, from the smallest position up to at most ROOM units (within half the
        range: valid positions on signed devices too), with room for ``hysteresis`` between them."""
        pitch = min(self.span // 2, ROOM) // (self.count + 2)
        if pitch < 8:
            not_applicable(f"a position range of {self.span} leaves no room for {self.count} windows")
        width = pitch // 2
        return {n: Cam(self.lowest + pitch * (n + 1), self.lowest + pitch * (n + 1) + width, hysteresis)
                for n in range(self.count)}

    @staticmethod
    def outside(cams: Mapping[int, Cam]) -> int:
        """A position below every window and its hysteresis band."""
        first = min(cams.values(), key=lambda cam: cam.low)
        return first.low - first.hysteresis - (first.high - first.low) // 2 - 1


@dataclass
class Remapped:
    """The TPDO a test mapped the CAM state into."""

    comm: int
    cob_id: int  # CAN-ID of the TPDO
