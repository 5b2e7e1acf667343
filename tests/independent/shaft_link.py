"""Shaft-drive plug-in for the independent device: ``--shaft-drive tests.independent.shaft_link:drive``.

The device prints its link address (``READY {"shaft": "HOST:PORT", ...}``); give it after ``=`` in the option
(``--shaft-drive tests.independent.shaft_link:drive=127.0.0.1:50123``) or in the environment variable
``INDEPENDENT_ENCODER_SHAFT``. A motor bench's plug-in has the same shape: a factory taking the
``ShaftDriveConfig`` and returning an object with ``turn_by`` and ``set_speed`` (``close`` optional).
"""

from __future__ import annotations

import os
import threading
from multiprocessing.connection import Client
from typing import TYPE_CHECKING

from .link import ADDRESS_ENV, AUTHKEY, parse_address

if TYPE_CHECKING:
    from encoder_conformance.dut.bench.actuator import ShaftDriveConfig


class ShaftLink:
    """Turns the independent device's shaft over its local link."""

    def __init__(self, address: tuple[str, int]) -> None:
        self.address = address
        self._lock = threading.Lock()
        self._connection = Client(address, authkey=AUTHKEY)

    def _call(self, command: str, *args: float) -> object:
        with self._lock:
            self._connection.send((command, args))
            ok, result = self._connection.recv()
        if not ok:
            raise RuntimeError(f"the device refused {command}{args}: {result}")
        return result

    def turn_by(self, revolutions: float) -> None:
        """Turn the shaft by ``revolutions`` (clockwise positive, looking at the shaft)."""
        self._call("turn_by", float(revolutions))

    def set_speed(self, revolutions_per_second: float) -> None:
        """Spin the shaft at a constant speed (0 stops it)."""
        self._call("set_speed", float(revolutions_per_second))

    def angle(self) -> float:
        """The shaft angle in revolutions (for diagnostics)."""
        return float(self._call("angle"))  # type: ignore[arg-type]

    def close(self) -> None:
        with self._lock:
            self._connection.close()


def drive(config: ShaftDriveConfig) -> ShaftLink:
    """The plug-in factory: the link at the option's argument, else at ``$INDEPENDENT_ENCODER_SHAFT``."""
    address = config.argument or os.environ.get(ADDRESS_ENV)
    if not address:
        raise ValueError(f"no shaft link address: give it as --shaft-drive {__name__}:drive=HOST:PORT or in the "
                         f"environment variable {ADDRESS_ENV} (the device prints it on its READY line)")
    return ShaftLink(parse_address(address))
