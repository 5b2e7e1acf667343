"""Custody: the snapshot as found, the journal of settings a test changed, the give-back (write order, aliased
entries, the reference point) and its record, so a device is left as found.
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.custody.aliased_values import entries_that_may_alias
    from encoder_conformance.dut.custody.custody import Custody
    from encoder_conformance.dut.custody.custody import IdentityMismatch
    from encoder_conformance.dut.custody.custody import PreflightError
    from encoder_conformance.dut.custody.face import CustodyFace
    from encoder_conformance.dut.custody.reference_custody import ReferenceCustody
    from encoder_conformance.dut.custody.settings_journal import SettingsJournal
    from encoder_conformance.dut.custody.snapshot import SNAPSHOT_FILE

__getattr__ = lazy_face(__name__, __file__)
