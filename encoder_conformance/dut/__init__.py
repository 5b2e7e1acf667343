"""The device under test, seen from the tester's side of the bus: ``DeviceUnderTest`` (``device.py``), the link to
it and one sub-package per protocol or concern, each with its face (its ``__init__``'s exports, what the suites
import): ``link`` (connection, frame log, the device link, waits, time budget), ``sdo``, ``nmt`` (commands and
states reached by transition), ``lss``, ``emcy``, ``tpdo``, ``store``, ``custody`` (snapshot, settings journal,
give-back, so a device is left as found) and ``bench`` (power switch, actuator, encoder function, shaft)."""

# the face exports what it imports
# ruff: noqa: F401

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.device import DeviceUnderTest

__getattr__ = lazy_face(__name__, __file__)
