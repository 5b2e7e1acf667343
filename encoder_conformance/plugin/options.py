"""Command-line options of the suite and their validation (errors name the option and the fix)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pytest

from ..bus_config import BusConfig, resolve_bus_config
from ..profile.loader import LoadedProfile, load_profile
from ..sim.faults import FAULTS

DEFAULT_PROFILE = "wachendorff-wdga-mt"
PROFILE_ENV = "ENCODER_CONFORMANCE_PROFILE"


@dataclass(frozen=True)
class RunSettings:
    """Everything the options decided, stashed on the config."""

    loaded: LoadedProfile
    bus: BusConfig
    node_id: int
    node_id_source: str
    allow_destructive: bool
    sim_faults: tuple[str, ...]
    sim_inprocess: bool
    sim_profile: LoadedProfile


SETTINGS = pytest.StashKey[RunSettings]()


def add_options(parser: pytest.Parser) -> None:
    group = parser.getgroup("encoder-conformance", "CANopen encoder conformance")
    group.addoption("--device-profile", default=None,
                    help=f"device profile id or YAML file. Environment variable: {PROFILE_ENV}. "
                         f"Default: {DEFAULT_PROFILE}")
    group.addoption("--can-interface", default=None,
                    help="python-can interface (pcan, kvaser, socketcan, ixxat, slcan, remote ...). "
                         "Default: python-can's configuration (CAN_INTERFACE, ~/can.conf); "
                         "none configured = the built-in simulator")
    group.addoption("--can-channel", default=None, help="python-can channel (PCAN_USBBUS1, can0, ws://...)")
    group.addoption("--can-bitrate", default=None, type=int, help="bit rate in bit/s")
    group.addoption("--node-id", default=None, type=int, help="node-id of the device (1..127). "
                    "Default: the profile's delivery node-id")
    group.addoption("--allow-destructive", action="store_true", default=False,
                    help="allow tests that change what the device remembers (store, restore, node-id). "
                         "Always allowed on the simulator")
    group.addoption("--sim-fault", action="append", default=[],
                    help="simulator only: inject a named fault (encoder-conformance faults lists them)")
    group.addoption("--sim-profile", default=None,
                    help="simulator only: the profile the twin plays (default: the --device-profile). "
                         "Checking a twin with another device's profile shows how a wrong profile fails")
    group.addoption("--sim-inprocess", action="store_true", default=False,
                    help="simulator only: run it in the test process on the virtual interface "
                         "(faster start, less accurate timing)")
    group.addoption("--report-dir", default=None,
                    help="directory for report.html, junit.xml and allure-results "
                         "(default reports/<timestamp>-<profile>/ when the suites run)")


def configure(config: pytest.Config) -> None:
    """Load the profile, resolve the bus and check option combinations; raises UsageError."""
    name = config.getoption("--device-profile") or os.environ.get(PROFILE_ENV) or DEFAULT_PROFILE
    loaded = load_profile(name)
    if loaded.profile.abstract:
        raise pytest.UsageError(
            f"--device-profile {name}: this profile is abstract (a base for variants); "
            f"choose one of the profiles that extend it (encoder-conformance profile list)"
        )
    bus = resolve_bus_config(
        config.getoption("--can-interface"), config.getoption("--can-channel"), config.getoption("--can-bitrate")
    )
    node_id = config.getoption("--node-id")
    source = "command line"
    if node_id is None:
        node_id, source = loaded.profile.bus.node_id, f"profile {loaded.profile.id} (delivery state)"
    if not 1 <= node_id <= 127:
        raise pytest.UsageError(f"--node-id {node_id}: a CANopen node-id is 1..127")
    faults = tuple(config.getoption("--sim-fault"))
    unknown = [f for f in faults if f not in FAULTS]
    if unknown:
        raise pytest.UsageError(
            f"--sim-fault {', '.join(unknown)}: unknown fault; known: {', '.join(sorted(FAULTS))}"
        )
    if faults and not bus.simulated:
        raise pytest.UsageError("--sim-fault only works with the built-in simulator; remove --can-interface")
    config.stash[SETTINGS] = RunSettings(
        loaded=loaded,
        bus=bus,
        node_id=node_id,
        node_id_source=source,
        allow_destructive=bool(config.getoption("--allow-destructive")) or bus.simulated,
        sim_faults=faults,
        sim_inprocess=bool(config.getoption("--sim-inprocess")),
        sim_profile=load_profile(config.getoption("--sim-profile")) if config.getoption("--sim-profile") else loaded,
    )


def settings_of(config: pytest.Config) -> RunSettings:
    return config.stash[SETTINGS]


def repo_root() -> Path:
    return Path(__file__).resolve().parents[2]
