"""Resolve the CAN bus configuration and remember where each setting came from.

Precedence (python-can's own, shown in the report header): command line > can.rc >
CAN_INTERFACE / CAN_CHANNEL / CAN_BITRATE / CAN_CONFIG > python-can config files. With no
interface anywhere, the built-in simulator is used.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any

import can

from encoder_conformance.errors import BusSetupError

SIMULATOR = "simulator"


@dataclass
class BusConfig:
    """The python-can keyword arguments plus the source of each one."""

    kwargs: dict[str, Any]
    sources: dict[str, str] = field(default_factory=dict)

    @property
    def simulated(self) -> bool:
        return self.kwargs.get("interface") == SIMULATOR

    def describe(self) -> str:
        parts = [f"{key}={value!r} ({self.sources.get(key, 'default')})" for key, value in self.kwargs.items()]
        return ", ".join(parts)


def _env_sources() -> dict[str, str]:
    sources = {}
    for key in ("interface", "channel", "bitrate"):
        env = f"CAN_{key.upper()}"
        if os.environ.get(env):
            sources[key] = f"environment {env}"
    if os.environ.get("CAN_CONFIG"):
        try:
            for key in json.loads(os.environ["CAN_CONFIG"]):
                sources.setdefault(key, "environment CAN_CONFIG")
        except ValueError:
            pass
    return sources


def _configured_interface() -> bool:
    """True if python-can's environment or can.rc names an interface (so a failure is not 'nothing set')."""
    if can.rc.get("interface") or os.environ.get("CAN_INTERFACE"):
        return True
    try:
        return "interface" in json.loads(os.environ.get("CAN_CONFIG") or "{}")
    except ValueError:
        return False


def resolve_bus_config(interface: str | None, channel: str | None, bitrate: int | None) -> BusConfig:
    """Merge command-line values with python-can's configuration sources."""
    given = {k: v for k, v in {"interface": interface, "channel": channel, "bitrate": bitrate}.items() if v}
    sources = {key: "command line" for key in given}
    if interface == SIMULATOR:
        return BusConfig({"interface": SIMULATOR}, {"interface": "command line"})
    try:
        resolved = can.util.load_config(config=given)
    except can.CanInterfaceNotImplementedError as exc:
        if given.get("interface") or _configured_interface():
            known = ", ".join(sorted(can.interfaces.VALID_INTERFACES))
            raise BusSetupError(f"CAN interface problem: {exc}; known interfaces: {known}") from None
        return BusConfig({"interface": SIMULATOR}, {"interface": "default (no CAN interface configured)"})
    env = _env_sources()
    for key in resolved:
        if key not in sources:
            sources[key] = "can.rc" if key in can.rc else env.get(key, "python-can config file")
    return BusConfig(dict(resolved), sources)


def resolve_bench_bus(interface: str | None, channel: str | None, bitrate: int | None, why: str) -> BusConfig:
    """The real bus a bench command (restore, lss) works on; BusSetupError (a usage error) if none is named,
    ``why`` saying what the built-in simulator would not do."""
    bus = resolve_bus_config(interface, channel, bitrate)
    if bus.simulated:
        raise BusSetupError(f"name the bus with --can-interface/--can-channel (or python-can's configuration); {why}")
    return bus
