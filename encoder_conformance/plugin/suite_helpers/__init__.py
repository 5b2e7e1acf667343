"""The suites' helpers that need pytest or a test's evidence (formerly ``suite_support/``): assertion helpers that
name expected, observed and the frames (``checks``), a stream's verdict (``periodic``), a fixture's put-back
(``teardown``), and the helpers of one area each (``cam``, ``emcy``, ``lss``, ``tpdo``, ``work_area``). Device
handling without pytest lives in ``dut/`` (the parameters a test may change safely: ``dut.store``).
Its face: the names below (``dut/face_exports.py``), what the suites and fixtures import."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.plugin.suite_helpers.cam import CHANNEL
    from encoder_conformance.plugin.suite_helpers.cam import CamChannel
    from encoder_conformance.plugin.suite_helpers.cam import Findings
    from encoder_conformance.plugin.suite_helpers.cam import Remapped
    from encoder_conformance.plugin.suite_helpers.cam import WINDOW_RULE
    from encoder_conformance.plugin.suite_helpers.cam import cam_names
    from encoder_conformance.plugin.suite_helpers.checks import abort_accepted
    from encoder_conformance.plugin.suite_helpers.checks import assert_abort
    from encoder_conformance.plugin.suite_helpers.checks import assert_one_answer
    from encoder_conformance.plugin.suite_helpers.checks import describe_value
    from encoder_conformance.plugin.suite_helpers.checks import documented_quirk
    from encoder_conformance.plugin.suite_helpers.checks import expected_aborts
    from encoder_conformance.plugin.suite_helpers.checks import inconclusive_if_host_late
    from encoder_conformance.plugin.suite_helpers.checks import judge_refusal
    from encoder_conformance.plugin.suite_helpers.emcy import EmcyAccess
    from encoder_conformance.plugin.suite_helpers.lss import destructive_if_self_stored
    from encoder_conformance.plugin.suite_helpers.lss import require_service
    from encoder_conformance.plugin.suite_helpers.periodic import judge_stream
    from encoder_conformance.plugin.suite_helpers.teardown import put_back
    from encoder_conformance.plugin.suite_helpers.tpdo import tpdo_under_test
    from encoder_conformance.plugin.suite_helpers.work_area import WorkArea

__getattr__ = lazy_face(__name__, __file__)
