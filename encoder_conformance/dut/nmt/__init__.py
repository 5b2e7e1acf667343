"""NMT: the one way between states (``nmt_states``), seen by what each state answers (the heartbeat), observers of
the NMT and heartbeat services, the state a reset ends in, errors a device keeps that hold a check.
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.nmt.boot_state import expected_after_reset
    from encoder_conformance.dut.nmt.boot_state import settled_state
    from encoder_conformance.dut.nmt.face import NmtFace
    from encoder_conformance.dut.nmt.face import STATES
    from encoder_conformance.dut.nmt.heartbeat_state import describe
    from encoder_conformance.dut.nmt.heartbeat_state import newest_state
    from encoder_conformance.dut.nmt.nmt_observer import HeartbeatObserver
    from encoder_conformance.dut.nmt.nmt_observer import NmtObserver
    from encoder_conformance.dut.nmt.nmt_observer import ServiceObserver
    from encoder_conformance.dut.nmt.nmt_preconditions import clear_left_error
    from encoder_conformance.dut.nmt.nmt_states import confirm
    from encoder_conformance.dut.nmt.nmt_states import reach
    from encoder_conformance.dut.nmt.nmt_states import return_to_preoperational
    from encoder_conformance.dut.nmt.nmt_states import start_operational
    from encoder_conformance.dut.nmt.persistent_error import describe_hold
    from encoder_conformance.dut.nmt.persistent_error import error_register
    from encoder_conformance.dut.nmt.persistent_error import raise_if_held_by_error
    from encoder_conformance.dut.nmt.persistent_error import raise_if_held_out_of

__getattr__ = lazy_face(__name__, __file__)
