"""TPDOs under test: choosing one, setting it up and putting it back (COB-ID, mapping, while invalid), the
stimuli it is sent on, capturing a periodic stream.
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.tpdo.face import Tpdos
    from encoder_conformance.dut.tpdo.pdo_mapping import Entry
    from encoder_conformance.dut.tpdo.pdo_mapping import MappingCustody
    from encoder_conformance.dut.tpdo.pdo_mapping import apply_mapping
    from encoder_conformance.dut.tpdo.pdo_mapping import describe
    from encoder_conformance.dut.tpdo.pdo_mapping import invalidate
    from encoder_conformance.dut.tpdo.pdo_mapping import read_mapping
    from encoder_conformance.dut.tpdo.periodic_capture import PeriodicCapture
    from encoder_conformance.dut.tpdo.periodic_capture import PeriodicStream
    from encoder_conformance.dut.tpdo.stimulus import pdo_stimulus
    from encoder_conformance.dut.tpdo.tpdo import Tpdo
    from encoder_conformance.dut.tpdo.tpdo import TpdoParameters
    from encoder_conformance.dut.tpdo.tpdo_choice import NoUsableTpdo
    from encoder_conformance.dut.tpdo.tpdo_choice import choose_tpdo
    from encoder_conformance.dut.tpdo.tpdo_choice import fixed_behaviour_tpdos
    from encoder_conformance.dut.tpdo.tpdo_under_test import TpdoUnderTest
    from encoder_conformance.dut.tpdo.tpdo_while_invalid import WhileInvalid

__getattr__ = lazy_face(__name__, __file__)
