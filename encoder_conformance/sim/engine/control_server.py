"""The twin's side of the control channel (``sim/control.py``): the server of a separate process, and the same
commands for a twin in the tester's own process (``LocalControl``)."""

from __future__ import annotations

import threading
from collections.abc import Callable
from multiprocessing.connection import Connection, Listener
from typing import Any

from encoder_conformance.sim.control import AUTHKEY, ControlApi
from encoder_conformance.sim.engine.host import SimulatorHost


def _each(nodes: list[Any], method: str) -> None:
    for node in nodes:
        getattr(node, method)()


def _execute(host: SimulatorHost, command: str, node_id: int | None, args: tuple[Any, ...]) -> Any:
    node = host.node(node_id)
    device = host.device_nodes(node)  # a redundant device's nodes share one power supply
    actions: dict[str, Callable[..., Any]] = {
        "power_cycle": lambda: _each(device, "power_cycle"),
        "power_off": lambda: _each(device, "power_off"),
        "power_on": lambda: _each(device, "power_on"),
        "turn_by": node.shaft.turn_by,
        "set_speed": node.shaft.set_speed,
        "raise_emcy": node.raise_emcy,
        "clear_emcy": node.clear_emcy,
        "describe": node.describe,
        "scheduler_lateness": host.scheduler.lateness_since,
    }
    if command not in actions:
        raise ValueError(f"unknown command {command!r}; known: {', '.join(sorted(actions))}")
    return actions[command](*args)


def serve_control(host: SimulatorHost, address: tuple[str, int]) -> tuple[str, int]:
    """Accept control clients on ``address`` in background threads; returns the bound address."""
    listener = Listener(address, authkey=AUTHKEY)

    def handle(conn: Connection) -> None:
        with conn:
            while True:
                try:
                    command, node_id, args = conn.recv()
                except (EOFError, OSError):
                    return
                try:
                    conn.send((True, _execute(host, command, node_id, args)))
                except Exception as exc:
                    conn.send((False, f"{type(exc).__name__}: {exc}"))

    def accept() -> None:
        while True:
            try:
                conn = listener.accept()
            except (OSError, EOFError):
                return
            threading.Thread(target=handle, args=(conn,), daemon=True).start()

    threading.Thread(target=accept, name="sim-control", daemon=True).start()
    bound = listener.address
    return bound[0], bound[1]


class LocalControl(ControlApi):
    """Same API for a simulator running in this process (--sim-inprocess, self-tests)."""

    def __init__(self, host: SimulatorHost, node_id: int | None = None) -> None:
        self._host = host
        self._node_id = node_id
        self._lock = threading.Lock()

    def _call(self, command: str, *args: Any) -> Any:
        with self._lock:
            return _execute(self._host, command, self._node_id, args)

    def close(self) -> None:
        pass
