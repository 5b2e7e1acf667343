"""The TPDO a test configures: a transmission type the profile lists but the device refuses is named as the
profile's claim that failed (a firmware team reads which line of its profile to check), not as a bare abort."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.dut.tpdo.tpdo_under_test import TpdoUnderTest


def _tpdo(listed: list[int]) -> TpdoUnderTest:
    def refuse(index: int, sub: int, data: bytes) -> None:
        raise SdoAbortedError(0x06090030)

    profile = SimpleNamespace(capabilities=SimpleNamespace(tpdo_transmission_types=listed),
                              entry=lambda index, sub: SimpleNamespace(writable=True))
    return TpdoUnderTest(SimpleNamespace(profile=profile), SimpleNamespace(write=refuse), 0x1800, 253)  # type: ignore[arg-type]


def test_a_listed_type_the_device_refuses_names_the_profile_claim():
    with pytest.raises(AssertionError, match=r"1800h.02 = 253 refused with 06090030h .*capabilities\.tpdo_transmis"):
        _tpdo([1, 253, 254, 255]).configure(trans_type=253)


def test_an_unlisted_type_keeps_the_abort():
    with pytest.raises(SdoAbortedError):
        _tpdo([1, 254, 255]).configure(trans_type=253)
