"""The bench around the device: power switch and power cycles, the actuator (EMCY stimulus, shaft drive), the encoder
function over SDO (settings, position, reference point) and the shaft mover.
Its face: the names below (``dut/face_exports.py``)."""

# the face exports what it imports, one name a line so that it reads as a list
# ruff: noqa: F401, I001

from typing import TYPE_CHECKING

from encoder_conformance.dut.face_exports import lazy_face

if TYPE_CHECKING:
    from encoder_conformance.dut.bench.actuator import BenchActuator
    from encoder_conformance.dut.bench.actuator import ErrorStimulus
    from encoder_conformance.dut.bench.actuator import ReturningShaft
    from encoder_conformance.dut.bench.actuator import ShaftDrive
    from encoder_conformance.dut.bench.actuator import hardware_bench
    from encoder_conformance.dut.bench.actuator import simulator_bench
    from encoder_conformance.dut.bench.encoder_access import EncoderAccess
    from encoder_conformance.dut.bench.encoder_bench import EncoderBench
    from encoder_conformance.dut.bench.position_mover import ShaftMover
    from encoder_conformance.dut.bench.power import BenchPower
    from encoder_conformance.dut.bench.power import HOW_TO_CONFIGURE
    from encoder_conformance.dut.bench.power import ManualPowerSwitch
    from encoder_conformance.dut.bench.power import PowerSwitch
    from encoder_conformance.dut.bench.power import PowerSwitchError
    from encoder_conformance.dut.bench.power import ShellPowerSwitch
    from encoder_conformance.dut.bench.power import SimulatorPowerSwitch
    from encoder_conformance.dut.bench.power_on import power_cycler
    from encoder_conformance.dut.bench.power_on import switch_off_and_on
    from encoder_conformance.dut.bench.reference_point import read_reference_point

__getattr__ = lazy_face(__name__, __file__)
