"""Open and close the tester's CAN connection with bounds: a run never hangs on its own bus.

python-can gives no timeout for opening an interface; python-can-remote blocks forever in its
HTTP handshake when an endpoint accepts the TCP connection but never answers (measured: over
300 s with no message). Opening runs in a helper thread that is abandoned after the bound.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from typing import Any, cast

import can
import canopen

from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.link.remote_masking import unmask_on_loopback
from encoder_conformance.dut.link.tracing_bus import TracingBus
from encoder_conformance.errors import BusSetupError

OPEN_TIMEOUT_S = 5.0
#: canopen's notifier waits this long per receive call; its default 1 s delays every disconnect by up to 1 s
NOTIFIER_CYCLE_S = 0.05
NOTIFIER_STOP_TIMEOUT_S = 1.0


def open_bus(kwargs: dict[str, Any], describe: str, timeout_s: float = OPEN_TIMEOUT_S) -> can.BusABC:
    """``can.Bus(**kwargs)``, or BusSetupError naming the settings and what to check."""
    result: list[can.BusABC] = []
    failure: list[BaseException] = []

    def attempt() -> None:
        try:
            result.append(can.Bus(**kwargs))
        except BaseException as exc:  # reported in the caller's thread
            failure.append(exc)

    thread = threading.Thread(target=attempt, name="open-can-bus", daemon=True)
    thread.start()
    thread.join(timeout_s)
    if result:
        return result[0]
    if failure:
        exc = failure[0]
        raise BusSetupError(
            f"cannot open the CAN bus with {describe}: {type(exc).__name__}: {exc}. "
            "Check --can-interface/--can-channel/--can-bitrate or python-can's configuration"
        )
    raise BusSetupError(
        f"the CAN interface did not open within {timeout_s:.0f} s ({describe}): the endpoint or driver does not "
        "answer. Check that the adapter is plugged in and free, or that the remote endpoint is a CAN server"
    )


def connect(kwargs: dict[str, Any], describe: str, frame_log: FrameLog) -> canopen.Network:
    """A connected canopen Network on a TracingBus, whose frames (both directions) go to ``frame_log``."""
    # the tester's own frames are logged as it sends them; echoed back they would pass for another node's
    bus = open_bus({**kwargs, "receive_own_messages": False}, describe)
    unmask_on_loopback(bus)  # python-can-remote to a server on this host: no per-byte masking (remote_masking.py)
    # cast: a TracingBus stands in for the bus it wraps (send and recv traced, every other attribute forwarded)
    network = canopen.Network(cast(can.BusABC, TracingBus(bus, frame_log, kwargs.get("channel"))))
    network.NOTIFIER_CYCLE = NOTIFIER_CYCLE_S
    network.NOTIFIER_SHUTDOWN_TIMEOUT = NOTIFIER_STOP_TIMEOUT_S
    network.listeners.append(frame_log)  # type: ignore[arg-type]  # why: canopen takes any can.Listener here
    network.connect()
    return network


@contextlib.contextmanager
def connected(kwargs: dict[str, Any], describe: str) -> Iterator[tuple[canopen.Network, FrameLog]]:
    """``connect`` with a frame log of its own, disconnected at the end; BusSetupError where the bus does not open."""
    frames = FrameLog()
    network = connect(kwargs, describe, frames)
    try:
        yield network, frames
    finally:
        disconnect(network)


def disconnect(network: canopen.Network) -> None:
    """Stop the notifier and shut the bus down; bounded, never raises."""
    with contextlib.suppress(Exception):
        network.disconnect()
