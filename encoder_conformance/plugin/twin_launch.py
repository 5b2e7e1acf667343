"""The built-in twin launched at session start, so that its start-up overlaps the collection of the tests; the
``simulator`` fixture (fixtures/simulator.py) takes it over, or starts one itself when none was launched."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pytest

from encoder_conformance.plugin.options import settings_of
from encoder_conformance.plugin.reporting import report_dir, runs_suites
from encoder_conformance.sim.control import ControlApi
from encoder_conformance.sim.process import LaunchedSimulator, launch_simulator

LAUNCHED = pytest.StashKey[LaunchedSimulator]()


@dataclass
class SimulatorEndpoint:
    """How the test side reaches a simulator: bus arguments plus the control channel."""

    bus_kwargs: dict[str, Any]
    control: ControlApi  # a separate process's socket, or the in-process host's LocalControl
    description: str


def separate_process(config: pytest.Config) -> bool:
    """The run simulates its device in a process of its own (the default without a CAN interface)."""
    settings = settings_of(config)
    return settings.bus.simulated and not settings.sim_inprocess


def launch_early(session: pytest.Session) -> None:
    """Launch the twin now (a run of the suites with a simulated device, not an xdist worker)."""
    config = session.config
    if not runs_suites(config) or not separate_process(config) or hasattr(config, "workerinput"):
        return
    settings = settings_of(config)
    folder = report_dir(config)
    factory = config._tmp_path_factory  # type: ignore[attr-defined]  # the tmp_path_factory fixture's
    log = (folder / "simulator.log") if folder else factory.mktemp("simlog") / "simulator.log"
    nvm = factory.mktemp("simulator") / "nvm.json"
    config.stash[LAUNCHED] = launch_simulator(str(settings.sim_profile.path), settings.node_id,
                                              list(settings.sim_faults), nvm, log, fork=True)


def take_launched(config: pytest.Config) -> LaunchedSimulator | None:
    """The twin launched at session start, handed over once (None: none was launched)."""
    launched = config.stash.get(LAUNCHED, None)
    if launched is not None:
        del config.stash[LAUNCHED]
    return launched


def abandon(config: pytest.Config) -> None:
    """At the session's end: a twin launched but never asked for is stopped."""
    launched = config.stash.get(LAUNCHED, None)
    if launched is not None:
        launched.abandon()
