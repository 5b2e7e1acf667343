"""What a device remembers: storing entries its own way (``persist``), counting the commands that wear its memory,
whether it shows what it stored after a restart, what it says at boot about its stored data; the parameters a test
may change safely, and a value to change them to (``changeable``).
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.store.changeable import STORE_GROUPS
    from encoder_conformance.dut.store.changeable import Changeable
    from encoder_conformance.dut.store.changeable import changeable_parameter
    from encoder_conformance.dut.store.changeable import other_valid_value
    from encoder_conformance.dut.store.face import StoreFace
    from encoder_conformance.dut.store.persist import CannotPersist
    from encoder_conformance.dut.store.persist import persist_entry
    from encoder_conformance.dut.store.store_watch import AUTO_STORED
    from encoder_conformance.dut.store.store_watch import StoreWatch

__getattr__ = lazy_face(__name__, __file__)
