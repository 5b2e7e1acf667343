"""The run's built-in twin, started one way: ``launch_early`` launches it at session start, so that its start-up
overlaps the collection of the tests; ``start_twin`` (the ``simulator`` fixture, fixtures/simulator.py) takes it
over, or starts one itself (in this process with ``--sim-inprocess``, or when none was launched). The paths of the
twin's files (the run's ``simulator.log``, its ``nvm.json``) are made here only."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from encoder_conformance.plugin.options import settings_of
from encoder_conformance.plugin.reporting import report_dir, runs_suites
from encoder_conformance.sim.control import ControlApi
from encoder_conformance.sim.process import LaunchedSimulator, SimulatorControl, launch_simulator
from encoder_conformance.sim.twin import start_in_process

LAUNCHED = pytest.StashKey[LaunchedSimulator]()


@dataclass
class SimulatorEndpoint:
    """How the test side reaches a simulator: bus arguments plus the control channel."""

    bus_kwargs: dict[str, Any]
    control: ControlApi  # a separate process's socket, or the in-process host's LocalControl
    description: str


@dataclass
class RunTwin:
    """The run's twin once started: how the tests reach it, and how it ends."""

    endpoint: SimulatorEndpoint
    stop: Callable[[], None]


def separate_process(config: pytest.Config) -> bool:
    """The run simulates its device in a process of its own (the default without a CAN interface)."""
    settings = settings_of(config)
    return settings.bus.simulated and not settings.sim_inprocess


def _nvm_file(config: pytest.Config) -> Path:
    """The twin's non-volatile memory: a file of the session's own, in pytest's temporary folder."""
    return config._tmp_path_factory.mktemp("simulator") / "nvm.json"  # type: ignore[attr-defined]  # the fixture's


def _launch(config: pytest.Config, fork: bool) -> LaunchedSimulator:
    """The twin in a process of its own; its log is the run's ``simulator.log`` (in pytest's temporary folder
    when the run writes no report)."""
    settings = settings_of(config)
    folder = report_dir(config)
    factory = config._tmp_path_factory  # type: ignore[attr-defined]  # the tmp_path_factory fixture's
    log = (folder / "simulator.log") if folder else factory.mktemp("simlog") / "simulator.log"
    return launch_simulator(str(settings.sim_profile.path), settings.node_id, list(settings.sim_faults),
                            _nvm_file(config), log, fork=fork)


def launch_early(session: pytest.Session) -> None:
    """Launch the twin now (a run of the suites with a simulated device, not an xdist worker)."""
    config = session.config
    if not runs_suites(config) or not separate_process(config) or hasattr(config, "workerinput"):
        return
    config.stash[LAUNCHED] = _launch(config, fork=True)


def _take_launched(config: pytest.Config) -> LaunchedSimulator | None:
    """The twin launched at session start, handed over once (None: none was launched)."""
    launched = config.stash.get(LAUNCHED, None)
    if launched is not None:
        del config.stash[LAUNCHED]
    return launched


def start_twin(config: pytest.Config) -> RunTwin:
    """The run's simulated device, serving: in this process (``--sim-inprocess``), or the twin launched at session
    start, or (none was) one launched now."""
    settings = settings_of(config)
    if settings.sim_inprocess:
        twin = start_in_process(settings.sim_profile.profile, settings.node_id, _nvm_file(config),
                                settings.sim_faults, f"sim-{id(config)}")
        return RunTwin(SimulatorEndpoint(twin.bus_kwargs, twin.control, "in-process"), twin.stop)
    launched = _take_launched(config)
    if launched is None:
        launched = _launch(config, fork=False)
    process = launched.ready()
    control = SimulatorControl(process.control)

    def stop() -> None:
        control.close()
        process.stop()

    return RunTwin(SimulatorEndpoint(process.bus_kwargs, control, f"separate process, {process.can_url}"), stop)


def abandon(config: pytest.Config) -> None:
    """At the session's end: a twin launched but never asked for is stopped."""
    launched = config.stash.get(LAUNCHED, None)
    if launched is not None:
        launched.abandon()
