"""The suite's pytest options (declared in option_table.py) and their validation (errors name the option and the
fix)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pytest

from encoder_conformance.config.bus import BusConfig, resolve_bus_config
from encoder_conformance.config.station import Station, StationError, StationPower, load_station
from encoder_conformance.dut.bench.actuator import ShaftDrivePlugin
from encoder_conformance.history.target import shown
from encoder_conformance.paths import DEFAULT_PROFILE
from encoder_conformance.plugin.option_table import PROFILE_ENV, TRACE_OPTION
from encoder_conformance.profile.loader import LoadedProfile, load_profile
from encoder_conformance.sim.fault_catalogue import SIMULATOR_DEVIATIONS as FAULTS  # faults and conformant variants


@dataclass(frozen=True)
class PowerSettings:
    """How the bench switches the device off and on (shell commands or the operator)."""

    manual: bool
    off_command: str | None
    on_command: str | None
    off_time_s: float
    source: str


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
    power: PowerSettings | None = None
    station: Station | None = None
    delivery_state: bool = False
    shaft_drive: ShaftDrivePlugin | None = None


SETTINGS = pytest.StashKey[RunSettings]()


def configure(config: pytest.Config) -> None:
    """Load the profile, resolve the bus and check option combinations; raises UsageError."""
    name = config.getoption("--ec-profile") or os.environ.get(PROFILE_ENV) or DEFAULT_PROFILE
    loaded = load_profile(name)
    if loaded.profile.abstract:
        raise pytest.UsageError(
            f"--profile {name}: this profile is abstract (a base for variants); "
            f"choose one of the profiles that extend it (encoder-conformance profile list)"
        )
    station_path = config.getoption("--ec-station")
    try:
        station = load_station(Path(station_path)) if station_path else None
    except StationError as exc:
        raise pytest.UsageError(str(exc)) from None
    bus = _bus_settings(config, station, station_path)
    node_id = config.getoption("--ec-node-id")
    source = "command line"
    if node_id is None and station is not None and station.node_id is not None:
        node_id, source = station.node_id, f"station {station_path}"
    if node_id is None:
        node_id, source = loaded.profile.bus.node_id, f"profile {loaded.profile.id} (delivery state)"
    if not 1 <= node_id <= 127:
        raise pytest.UsageError(f"--node-id {node_id}: a CANopen node-id is 1..127")
    faults = tuple(config.getoption("--ec-sim-fault"))
    unknown = [f for f in faults if f not in FAULTS]
    if unknown:
        raise pytest.UsageError(
            f"--sim-fault {', '.join(unknown)}: unknown fault; known: {', '.join(sorted(FAULTS))}"
        )
    if faults and not bus.simulated:
        raise pytest.UsageError("--sim-fault only works with the built-in simulator; remove --can-interface")
    accepting = config.getoption("--ec-run-kind", default="run") == "accept"
    if accepting and config.getoption("--ec-allow-destructive"):
        raise pytest.UsageError("--allow-destructive: an acceptance changes nothing the device remembers; use 'run'")
    config.stash[SETTINGS] = RunSettings(
        loaded=loaded,
        bus=bus,
        node_id=node_id,
        node_id_source=source,
        # an acceptance does on the twin what it does on a bench: nothing destructive, defaults as found
        allow_destructive=bool(config.getoption("--ec-allow-destructive")) or (bus.simulated and not accepting),
        sim_faults=faults,
        sim_inprocess=bool(config.getoption("--ec-sim-inprocess")),
        sim_profile=load_profile(sim_profile) if (sim_profile := config.getoption("--ec-sim-profile")) else loaded,
        power=_power_settings(config, station, station_path, bus.simulated),
        station=station,
        delivery_state=bool(config.getoption("--ec-delivery-state")) or accepting,  # goods-in: fresh from the factory
        shaft_drive=_shaft_drive(config, station, bus.simulated),
    )


def _shaft_drive(config: pytest.Config, station: Station | None, simulated: bool) -> ShaftDrivePlugin | None:
    """The --shaft-drive plug-in (or the station's), imported now so that a wrong name is a usage error before any
    test."""
    spec = config.getoption("--ec-shaft-drive")
    if spec is None and station is not None and station.shaft_drive is not None and not simulated:
        spec = station.shaft_drive
    if spec is None:
        return None
    if simulated:
        raise pytest.UsageError("--shaft-drive is for a bench: the built-in simulator turns its own shaft")
    try:
        return ShaftDrivePlugin.load(spec)
    except ValueError as exc:
        raise pytest.UsageError(str(exc)) from None


def _bus_settings(config: pytest.Config, station: Station | None, station_path: str | None) -> BusConfig:
    """Command line over the station file over python-can's own configuration."""
    given = {key: config.getoption(f"--ec-can-{key}") for key in ("interface", "channel", "bitrate")}
    from_station = set()
    if station is not None and station.can is not None:
        for key, value in station.can.model_dump().items():
            if given[key] is None and value is not None:
                given[key] = value
                from_station.add(key)
    bus = resolve_bus_config(given["interface"], given["channel"], given["bitrate"])
    for key in from_station:
        bus.sources[key] = f"station {station_path}"
    return bus


def _power_settings(config: pytest.Config, station: Station | None, station_path: str | None,
                    simulated: bool) -> PowerSettings | None:
    """The bench's power switch from the options (or the station file); None if there is none."""
    off_cmd, on_cmd = config.getoption("--ec-power-off-cmd"), config.getoption("--ec-power-on-cmd")
    manual = bool(config.getoption("--ec-power-manual"))
    off_time = config.getoption("--ec-power-off-time")
    if (off_cmd is None) != (on_cmd is None):
        raise pytest.UsageError("--power-off-cmd and --power-on-cmd go together: give both commands")
    if manual and off_cmd:
        raise pytest.UsageError("--power-manual and --power-off-cmd/--power-on-cmd exclude each other: choose one")
    if off_time is not None and not 0 <= off_time <= 60:
        raise pytest.UsageError(f"--power-off-time {off_time}: give 0 .. 60 seconds")
    if (off_cmd or manual) and simulated:
        raise pytest.UsageError("--power-* options are for a bench: the built-in simulator has its own power switch")
    if off_cmd or manual:
        return PowerSettings(manual, off_cmd, on_cmd, 1.0 if off_time is None else off_time, "command line")
    power = station.power if station is not None else None
    if power == "manual":
        return PowerSettings(True, None, None, off_time or 0.0, f"station {station_path}")
    if isinstance(power, StationPower):
        return PowerSettings(False, power.off_command, power.on_command,
                             power.off_time_s if off_time is None else off_time,
                             f"station {station_path}")
    return None


def bench_settings(settings: RunSettings, station_path: str | None, shaft_option: str | None) -> dict[str, str]:
    """The station's settings beyond the bus and node-id, each with its source (for the report and the summary)."""
    station, path = settings.station, station_path
    from_station = f"from station {path}"
    values: dict[str, str] = {}
    if station is not None:
        values["station"] = f"{station.station} ({from_station})"
        if station.operator:
            values["operator"] = f"{station.operator} ({from_station})"
        if station.reports is not None:
            values["reports"] = f"{station.reports} ({from_station})"
        if station.history is not None:  # a URL's password is not shown
            values["history"] = f"{shown(station.history)} ({from_station})"
    power = settings.power
    if power is not None:
        how = "operator (asked at the terminal)" if power.manual else f"{power.off_command} / {power.on_command}"
        values["power switch"] = f"{how}, off {power.off_time_s:g} s (from {power.source})"
    if settings.shaft_drive is not None:
        values["shaft drive"] = f"{settings.shaft_drive.spec} (from {'command line' if shaft_option else from_station})"
    return values


def settings_of(config: pytest.Config) -> RunSettings:
    return config.stash[SETTINGS]


def trace_policy(config: pytest.Config) -> str:
    """Which tests keep their bus trace: failed (and warnings), all, or none."""
    return str(config.getoption(TRACE_OPTION, default="failed"))
