"""The engine's entry points for the tester side: what a process serving twins runs (``encoder-conformance sim``,
a forked run twin), a twin in the tester's own process (``--sim-inprocess``), and which of the twin's methods a
deviation overrides (the variant matrix). Each imports the engine (``sim/engine/``) when called: importing this
module loads none of it."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from encoder_conformance.sim.control import ControlApi

if TYPE_CHECKING:
    from encoder_conformance.profile.schema import DeviceProfile
    from encoder_conformance.sim.engine.serve import NodePlan

__all__ = ["SERVE_MODULE", "InProcessTwin", "overridden_methods", "plan_nodes", "serve", "start_in_process"]

#: the engine's module a twin's process runs: a process that forks twins (the fork server of suite sessions) imports
#: it ahead, so that each twin serves at once
SERVE_MODULE = "encoder_conformance.sim.engine.serve"


def plan_nodes(profiles: list[str], node_ids: list[int], copies: int = 1,
               unconfigured: bool = False) -> list[NodePlan]:
    """The nodes ``sim`` serves; ValueError says what is wrong with the combination (a usage error)."""
    from encoder_conformance.sim.engine.serve import plan_nodes as plan

    return plan(profiles, node_ids, copies, unconfigured)


def serve(plan: list[NodePlan], listen: str, control: str | None, faults: list[str], nvm: Path | None,
          ready_line: bool, can_bus: tuple[str, str] | None = None) -> int:
    """Serve the planned nodes until signalled (the twin process's main); ValueError: a port or the CAN bus
    could not be had (a usage error)."""
    from encoder_conformance.sim.engine.serve import serve as serve_nodes

    return serve_nodes(plan, listen, control, faults, nvm, ready_line, can_bus)


@dataclass
class InProcessTwin:
    """A twin in this process, on a python-can virtual channel: how the test side reaches it, and its end."""

    bus_kwargs: dict[str, Any]
    control: ControlApi  # the commands of the control channel, carried out in this process
    stop: Callable[[], None]


def start_in_process(profile: DeviceProfile, node_id: int | None, nvm: Path, faults: Iterable[str],
                     channel: str) -> InProcessTwin:
    """The profile's twin (with the redundant interface's other node of a ``second_node`` quirk) on ``channel``."""
    from encoder_conformance.sim.engine.control_server import LocalControl
    from encoder_conformance.sim.engine.faults import FaultSet
    from encoder_conformance.sim.engine.host import SimulatorHost

    host = SimulatorHost(channel=channel)
    host.add_node(profile, node_id, nvm, FaultSet(faults))
    host.add_siblings()  # second_node quirk: the redundant interface's other node
    return InProcessTwin({"interface": "virtual", "channel": host.channel}, LocalControl(host), host.shutdown)


def overridden_methods(deviation: str) -> frozenset[tuple[str, str]]:
    """(behaviour, method) pairs the mixins of a fault or conformant variant override in the twin."""
    from encoder_conformance.sim.engine import node  # noqa: F401  # imports every behaviour, so every mixin is declared
    from encoder_conformance.sim.engine.faults import mixins_of

    return frozenset((behaviour.__name__, name) for behaviour, mixin in mixins_of(deviation)
                     for name in vars(mixin) if not name.startswith("__"))
