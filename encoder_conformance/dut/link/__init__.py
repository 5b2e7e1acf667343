"""The link to the device: the bus connection and its frame log (every test's trace), the device object with
raw frames and its liveness, the windows a wait owes (answer; silence, sized from the device's measured answer
times: answer_times.py, windows.py), the time budget the waits are booked in, the host's clock and lateness, the
ledger of late frames (``late_frames.py``).
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.link.answer_times import AnswerTimes
    from encoder_conformance.dut.link.answer_times import measure_sdo
    from encoder_conformance.dut.link.clock import frame_clock
    from encoder_conformance.dut.link.device import DeviceLink
    from encoder_conformance.dut.link.device import SdoAborted
    from encoder_conformance.dut.link.device import answer_window
    from encoder_conformance.dut.link.frames import FrameLog
    from encoder_conformance.dut.link.frames import Mark
    from encoder_conformance.dut.link.frames import Predicate
    from encoder_conformance.dut.link.frames import format_frames
    from encoder_conformance.dut.link.frames import received_on
    from encoder_conformance.dut.link.late_frames import NO_PDO_OUTSIDE_OPERATIONAL
    from encoder_conformance.dut.link.late_frames import NO_SDO_IN_STOPPED
    from encoder_conformance.dut.link.latency_probe import HostLatency
    from encoder_conformance.dut.link.latency_probe import LatencyProbe
    from encoder_conformance.dut.link.latency_probe import TwinLateness
    from encoder_conformance.dut.link.windows import Window
    from encoder_conformance.dut.link.windows import Windows

__getattr__ = lazy_face(__name__, __file__)
