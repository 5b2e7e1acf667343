"""EMCY: the ways to make a device send an emergency (the bench's error stimulus, a SYNC of the wrong length).
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.emcy.emcy_trigger import BENCH_OTHER_CODE
    from encoder_conformance.dut.emcy.emcy_trigger import BenchError
    from encoder_conformance.dut.emcy.emcy_trigger import EmcyCobId
    from encoder_conformance.dut.emcy.emcy_trigger import EmcyTrigger
    from encoder_conformance.dut.emcy.emcy_trigger import HeartbeatTimeout
    from encoder_conformance.dut.emcy.emcy_trigger import SyncLengthError
    from encoder_conformance.dut.emcy.emcy_trigger import choose_trigger
    from encoder_conformance.dut.emcy.emcy_trigger import emcy_code
    from encoder_conformance.dut.emcy.emcy_trigger import is_any_emcy
    from encoder_conformance.dut.emcy.face import EmcyFace

__getattr__ = lazy_face(__name__, __file__)
