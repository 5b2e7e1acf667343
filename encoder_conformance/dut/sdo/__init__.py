"""SDO: the byte-exact client and its raw frames, words for a failure's frames, a patient read for custody, the identity
read, what the start-up check's frames show.
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.sdo.face import SdoFace
    from encoder_conformance.dut.sdo.identity import NO_SERIAL
    from encoder_conformance.dut.sdo.identity import read_identity
    from encoder_conformance.dut.sdo.identity import serial_650b_key
    from encoder_conformance.dut.sdo.sdo_client import SdoProtocolClient
    from encoder_conformance.dut.sdo.sdo_client import echoes
    from encoder_conformance.dut.sdo.sdo_frames import SdoResponse
    from encoder_conformance.dut.sdo.sdo_frames import abort_name
    from encoder_conformance.dut.sdo.sdo_frames import upload_request

__getattr__ = lazy_face(__name__, __file__)
