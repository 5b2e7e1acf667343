"""LSS: the master (the services' frames), the device's LSS states (reached by ``LssDevice.transition``) and
steps, finding nodes, the LSS put-back.
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.lss.face import LssFace
    from encoder_conformance.dut.lss.lss_device import LSS_STATES
    from encoder_conformance.dut.lss.lss_device import LssDevice
    from encoder_conformance.dut.lss.lss_device import expect_success
    from encoder_conformance.dut.lss.lss_device import table_index
    from encoder_conformance.dut.lss.lss_master import LssAddress
    from encoder_conformance.dut.lss.lss_master import LssMaster
    from encoder_conformance.dut.lss.lss_steps import SWITCH_DELAY_MS
    from encoder_conformance.dut.lss.lss_steps import activate
    from encoder_conformance.dut.lss.lss_steps import cob_ids_not_reset
    from encoder_conformance.dut.lss.lss_steps import manual_excludes
    from encoder_conformance.dut.lss.lss_steps import stored_node_id_survives_power_cycle

__getattr__ = lazy_face(__name__, __file__)
