"""Command-line options of the suite and their validation (errors name the option and the fix)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pytest

from encoder_conformance.config.bus import BusConfig, resolve_bus_config
from encoder_conformance.config.station import Station, StationError, StationPower, load_station
from encoder_conformance.dut.actuator import ShaftDrivePlugin
from encoder_conformance.paths import DEFAULT_PROFILE
from encoder_conformance.plugin import verdicts
from encoder_conformance.profile.loader import LoadedProfile, load_profile
from encoder_conformance.sim.fault_catalogue import SIMULATOR_DEVIATIONS as FAULTS  # faults and conformant variants

PROFILE_ENV = "ENCODER_CONFORMANCE_PROFILE"
TRACE_OPTION = "--bus-trace"
TRACE_POLICIES = ("failed", "all", "none")


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
    group.addoption("--station", default=None,
                    help="station file (TOML, or YAML): the bench's CAN adapter, node-id, power switch, operator, "
                         "motor plug-in, report and history locations; command-line options override it")
    group.addoption("--power-off-cmd", default=None,
                    help="shell command that switches the device off (with --power-on-cmd): the power-cycle "
                         "tests run on the bench instead of skipping")
    group.addoption("--power-on-cmd", default=None, help="shell command that switches the device on")
    group.addoption("--power-manual", action="store_true", default=False,
                    help="ask the operator at the terminal to switch the power off and on")
    group.addoption("--power-off-time", default=None, type=float,
                    help="seconds the power stays off in a power cycle (default 1.0, 0 on the simulator)")
    group.addoption("--shaft-drive", default=None, metavar="MODULE:FACTORY[=ARGUMENT]",
                    help="bench only: a plug-in that turns the encoder's shaft (a motor): FACTORY(config) returns an "
                         "object with turn_by(revolutions) and set_speed(revolutions_per_second); config.argument is "
                         "the text after '='. Without it the tests that need rotation skip on a bench")
    group.addoption("--label-serial", default=None, type=int, metavar="NUMBER",
                    help="the serial number printed on the device's label (decimal): the identity tests check that the "
                         "device reports it (1018h sub 4, else 650Bh), and the history finds a device that reports "
                         "none by it. On the built-in simulator: the twin's own (profile simulator.serial_number)")
    group.addoption("--delivery-state", action="store_true", default=False,
                    help="the device is in its delivery state (never configured): check factory defaults "
                         "as found, without restoring defaults first (no --allow-destructive needed)")
    group.addoption("--report-dir", default=None,
                    help="directory for report.html, junit.xml, traces (and allure-results with --allure) "
                         "(default reports/<timestamp>-<profile>/ when the suites run)")
    verdicts.add_option(group)
    group.addoption("--abort-codes", choices=("exact", "family"), default="exact",
                    help="how SDO abort codes are judged: 'exact' (default) the code CiA 301 or the manual names for "
                         "the situation; 'family' any code that differs only in its last digit (06090031h for "
                         "06090030h), as the CiA conformance test tool accepts")
    group.addoption("--budget", default=1.0, type=float, metavar="SECONDS",
                    help="wall-clock time each property test (hypothesis sequences against the device) may spend "
                         "generating examples (default 1 s; raise it for long bench runs)")
    group.addoption("--fuzz-budget", default=None, type=float, metavar="SECONDS",
                    help="wall-clock time each SDO fuzz test may spend sending examples; once spent, it stops "
                         "(default: no limit, the hypothesis profile's example count decides; set it on a bench)")
    group.addoption(TRACE_OPTION, choices=TRACE_POLICIES, default="failed",
                    help="which tests keep their bus trace (traces/<test>.asc and .log, candump format): 'failed' "
                         "(default: failed, error and warning tests), 'all', or 'none' (pytest's own --trace is its "
                         "debugger; `encoder-conformance run --trace` sets this)")
    group.addoption("--allure", action="store_true", default=False,
                    help="also write allure-pytest results (allure-results/ in the report folder; render with "
                         "`npx allure generate`). Off by default: about 3,400 files and 3 s of a 14 s WDGA run")


def configure(config: pytest.Config) -> None:
    """Load the profile, resolve the bus and check option combinations; raises UsageError."""
    name = config.getoption("--device-profile") or os.environ.get(PROFILE_ENV) or DEFAULT_PROFILE
    loaded = load_profile(name)
    if loaded.profile.abstract:
        raise pytest.UsageError(
            f"--device-profile {name}: this profile is abstract (a base for variants); "
            f"choose one of the profiles that extend it (encoder-conformance profile list)"
        )
    station_path = config.getoption("--station")
    try:
        station = load_station(Path(station_path)) if station_path else None
    except StationError as exc:
        raise pytest.UsageError(str(exc)) from None
    bus = _bus_settings(config, station, station_path)
    node_id = config.getoption("--node-id")
    source = "command line"
    if node_id is None and station is not None and station.node_id is not None:
        node_id, source = station.node_id, f"station {station_path}"
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
    accepting = config.getoption("--run-kind", default="run") == "accept"
    if accepting and config.getoption("--allow-destructive"):
        raise pytest.UsageError("--allow-destructive: an acceptance changes nothing the device remembers; use 'run'")
    config.stash[SETTINGS] = RunSettings(
        loaded=loaded,
        bus=bus,
        node_id=node_id,
        node_id_source=source,
        # an acceptance does on the twin what it does on a bench: nothing destructive, defaults as found
        allow_destructive=bool(config.getoption("--allow-destructive")) or (bus.simulated and not accepting),
        sim_faults=faults,
        sim_inprocess=bool(config.getoption("--sim-inprocess")),
        sim_profile=load_profile(config.getoption("--sim-profile")) if config.getoption("--sim-profile") else loaded,
        power=_power_settings(config, station, station_path, bus.simulated),
        station=station,
        delivery_state=bool(config.getoption("--delivery-state")) or accepting,  # goods-in: fresh from the factory
        shaft_drive=_shaft_drive(config, station, bus.simulated),
    )


def _shaft_drive(config: pytest.Config, station: Station | None, simulated: bool) -> ShaftDrivePlugin | None:
    """The --shaft-drive plug-in (or the station's), imported now so that a wrong name is a usage error before any
    test."""
    spec = config.getoption("--shaft-drive")
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
    given = {key: config.getoption(f"--can-{key}") for key in ("interface", "channel", "bitrate")}
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
    off_cmd, on_cmd = config.getoption("--power-off-cmd"), config.getoption("--power-on-cmd")
    manual = bool(config.getoption("--power-manual"))
    off_time = config.getoption("--power-off-time")
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
        for key in ("reports", "history"):
            if getattr(station, key) is not None:
                values[key] = f"{getattr(station, key)} ({from_station})"
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
