"""The simulator's control channel (power, shaft, EMCY stimulus): the API, the server, the in-process form.

Uses the standard library's multiprocessing.connection (authenticated, pickled tuples) rather
than a hand-written protocol. This module imports nothing else of the simulator at run time, so
the client (``encoder_conformance.sim.process``) stays light: a bench's power command starts it often.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from multiprocessing.connection import Connection, Listener
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from encoder_conformance.sim.host import SimulatorHost

AUTHKEY = b"encoder-conformance-sim"


def parse_address(text: str) -> tuple[str, int]:
    """'HOST:PORT' (or ':PORT') -> (host, port); ValueError names the text."""
    host, _, port = text.rpartition(":")
    if not port.isdigit():
        raise ValueError(f"{text!r} is not HOST:PORT")
    return host or "127.0.0.1", int(port)


class ControlApi:
    """What the test side may ask of a simulated device; ``_call`` carries it out."""

    def _call(self, command: str, *args: Any) -> Any:
        raise NotImplementedError

    def power_cycle(self) -> None:
        self._call("power_cycle")

    def power_off(self) -> None:
        self._call("power_off")

    def power_on(self) -> None:
        self._call("power_on")

    def turn_by(self, revolutions: float) -> None:
        self._call("turn_by", revolutions)

    def set_speed(self, revolutions_per_second: float) -> None:
        self._call("set_speed", revolutions_per_second)

    def raise_emcy(self, code: int, register_bits: int, info: bytes = b"") -> None:
        self._call("raise_emcy", code, register_bits, info)

    def clear_emcy(self) -> None:
        self._call("clear_emcy")

    def describe(self) -> dict[str, Any]:
        return self._call("describe")

    def scheduler_lateness(self, since: float) -> list[tuple[float, float]]:
        """How late the twin's timing thread ran each job after ``since`` (time.time()): (when, ms late)."""
        return self._call("scheduler_lateness", since)

    def close(self) -> None:
        """Release the channel."""


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
