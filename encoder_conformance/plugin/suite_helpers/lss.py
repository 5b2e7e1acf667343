"""Skips of the LSS suite: a service the profile does not declare, a configuration that would write the device's
memory where destructive tests are not allowed."""

from __future__ import annotations

import pytest

from encoder_conformance.dut.lss import LssDevice
from encoder_conformance.plugin.options import settings_of
from encoder_conformance.plugin.skips import not_applicable, not_selected


def require_service(device: LssDevice, *services: str) -> None:
    """Skip with the reason where the profile does not declare an LSS service the test needs."""
    missing = [s for s in services if s not in device.services]
    if missing:
        not_applicable(f"{device.dut.profile.id} does not declare LSS {', '.join(missing)} "
                    f"(capabilities.lss)")


def destructive_if_self_stored(device: LssDevice, config: pytest.Config, what: str) -> None:
    """On a device that stores a configured ``what`` ("node_id"/"bit_timing") by itself, configuring another
    value writes its memory: skip unless destructive tests are allowed (they are on the simulator)."""
    if what in device.auto_stored and not settings_of(config).allow_destructive:
        not_selected(f"destructive on this device (it stores a configured {what.replace('_', '-')} by itself, quirk "
                    "lss_config_auto_stored): run with --allow-destructive")
