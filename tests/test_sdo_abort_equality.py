"""canopen's SdoAbortedError compares itself with any exception (``self.code == other.code``): hypothesis, which
compares the failures it found (``InterestingOrigin``), crashed with ``AttributeError: 'AssertionError' object
has no attribute 'code'`` when a test turned a refused SDO write into an AssertionError (issue 26). The dut
layer raises its own abort (``dut.device.SdoAborted``) with a safe comparison, outside canopen's except block."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from canopen.sdo.exceptions import SdoAbortedError
from hypothesis import given, settings
from hypothesis import strategies as st

from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link.device import SdoAborted
from encoder_conformance.dut.link.frames import FrameLog

STATE_REFUSED = 0x08000022  # CiA 301 §7.2.4.3.17: "... because of the present device state"


class _RefusingSdo:
    """canopen's SDO client as a device that refuses every write in the present state."""

    RESPONSE_TIMEOUT = 0.3

    def download(self, index: int, sub: int, data: bytes) -> None:
        raise SdoAbortedError(STATE_REFUSED)

    def upload(self, index: int, sub: int) -> bytes:
        raise SdoAbortedError(STATE_REFUSED)


def _dut() -> DeviceUnderTest:
    """A DeviceUnderTest around the refusing client (no bus: write and read only call canopen)."""
    dut = DeviceUnderTest.__new__(DeviceUnderTest)
    dut.frames, dut.node = FrameLog(), SimpleNamespace(sdo=_RefusingSdo())
    dut._lost, dut.bench_failure, dut.stopping, dut._custody = None, None, None, SimpleNamespace(active=False)
    return dut


def test_refused_write_turned_into_an_assertion_is_reported_by_hypothesis():
    """As suites/test_nmt_state_machine.py's write rule does: hypothesis must report the AssertionError."""
    dut = _dut()

    @settings(max_examples=3, database=None, deadline=None)
    @given(st.integers(0, 10))
    def write(value: int) -> None:
        try:
            dut.write(0x1800, 1, value.to_bytes(4, "little"))
        except SdoAbortedError as exc:
            raise AssertionError(f"write refused in operational: {exc}") from None

    with pytest.raises(AssertionError, match="refused in operational"):
        write()


def test_the_dut_layer_abort_is_canopens_and_compares_safely():
    dut = _dut()
    with pytest.raises(SdoAbortedError) as caught:
        dut.read(0x1000, 0)
    assert isinstance(caught.value, SdoAborted)
    assert caught.value.code == STATE_REFUSED
    assert caught.value.__context__ is None, "canopen's own exception must not travel in the context"
    assert caught.value != AssertionError("x")
    assert caught.value == SdoAbortedError(STATE_REFUSED)
    assert str(caught.value).startswith("Code 0x08000022")
