"""The local channel between the shaft-drive plug-in (tester side) and the device process (the shaft).

A ``multiprocessing.connection`` link on localhost: the plug-in sends ``(command, argument)``, the device
answers ``(True, result)`` or ``(False, reason)``. Commands: ``turn_by`` (revolutions, clockwise positive
looking at the shaft), ``set_speed`` (revolutions per second), ``angle`` (the shaft angle in revolutions).
"""

from __future__ import annotations

import signal
import threading

AUTHKEY = b"independent-encoder-shaft"
#: environment variable with the link address HOST:PORT (the plug-in's fallback when the option gives none)
ADDRESS_ENV = "INDEPENDENT_ENCODER_SHAFT"
COMMANDS = ("turn_by", "set_speed", "angle")


def parse_address(text: str) -> tuple[str, int]:
    """'127.0.0.1:50123' -> ('127.0.0.1', 50123); ValueError says what is wrong."""
    host, sep, port = text.strip().rpartition(":")
    if not sep or not host or not port.isdigit():
        raise ValueError(f"shaft link address {text!r}: give HOST:PORT, e.g. 127.0.0.1:50123")
    return host, int(port)


def format_address(address: tuple[str, int]) -> str:
    return f"{address[0]}:{address[1]}"


def wait_for_sigterm() -> None:
    """Serve until SIGTERM or Ctrl-C (the test harness stops the processes with SIGTERM)."""
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        while not stop.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
