"""A fixture's teardown: put back what a test changed; what could not be put back fails the test."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from encoder_conformance.dut import DeviceUnderTest


def put_back(dut: DeviceUnderTest, restore: Callable[[], list[str]]) -> None:
    """``restore`` while the device is usable; what it could not put back fails the test (unless the device went
    away meanwhile: then the run's restore takes over)."""
    if dut.usable:
        problems = restore()
        if problems and dut.usable:
            pytest.fail("could not put back: " + "; ".join(problems), pytrace=False)
