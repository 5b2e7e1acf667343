"""The simulator's control channel (power, shaft, EMCY stimulus): what the test side may ask, and the channel's
address and key. The twin serves it (``sim/engine/control_server.py``).

Uses the standard library's multiprocessing.connection (authenticated, pickled tuples) rather
than a hand-written protocol. This module imports nothing else of the simulator, so the client
(``encoder_conformance.sim.process``) stays light: a bench's power command starts it often.
"""

from __future__ import annotations

from typing import Any

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
