"""What the suites use beside their fixtures: assertion helpers that name expected, observed and the frames
(``checks``), the parameters a test may change safely (``parameters``), and the helpers of one area each that
need pytest or the evidence (``cam``, ``emcy``, ``lss``, ``periodic``, ``tpdo``, ``work_area``, ``teardown``).
Device-handling code without pytest lives in ``dut/``.
Its face: the names below (``dut/face_exports.py``), what the suites and fixtures import."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.suite_support.cam import CHANNEL
    from encoder_conformance.suite_support.cam import CamChannel
    from encoder_conformance.suite_support.cam import Findings
    from encoder_conformance.suite_support.cam import Remapped
    from encoder_conformance.suite_support.cam import WINDOW_RULE
    from encoder_conformance.suite_support.cam import cam_names
    from encoder_conformance.suite_support.checks import abort_accepted
    from encoder_conformance.suite_support.checks import assert_abort
    from encoder_conformance.suite_support.checks import assert_one_answer
    from encoder_conformance.suite_support.checks import describe_value
    from encoder_conformance.suite_support.checks import documented_quirk
    from encoder_conformance.suite_support.checks import expected_aborts
    from encoder_conformance.suite_support.checks import inconclusive_if_host_late
    from encoder_conformance.suite_support.checks import judge_refusal
    from encoder_conformance.suite_support.emcy import EmcyAccess
    from encoder_conformance.suite_support.lss import destructive_if_self_stored
    from encoder_conformance.suite_support.lss import require_service
    from encoder_conformance.suite_support.parameters import STORE_GROUPS
    from encoder_conformance.suite_support.parameters import changeable_parameter
    from encoder_conformance.suite_support.parameters import other_valid_value
    from encoder_conformance.suite_support.periodic import judge_stream
    from encoder_conformance.suite_support.teardown import put_back
    from encoder_conformance.suite_support.tpdo import tpdo_under_test
    from encoder_conformance.suite_support.work_area import WorkArea

__getattr__ = lazy_face(__name__, __file__)
