"""SDO round trips per second against the twin in its own process: raw python-can, canopen's client,
and the DUT layer's two paths. Not collected by pytest; run ``python tests/perf_sdo.py [SECONDS]``.

Issue 8 asks the DUT paths to stay within 10 % of raw python-can on the same twin.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable

import can

from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link.connection import connect, disconnect
from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.sdo.sdo_frames import upload_request
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.sim.process import start_simulator

PROFILE = "wachendorff-wdga-mt"


def rate(call: Callable[[], object], seconds: float) -> float:
    """Calls per second of ``call`` over ``seconds`` (after 50 warm-up calls)."""
    for _ in range(50):
        call()
    done, start = 0, time.perf_counter()
    while (elapsed := time.perf_counter() - start) < seconds:
        call()
        done += 1
    return done / elapsed


def raw_python_can(bus_kwargs: dict, node_id: int, seconds: float) -> float:
    bus = can.Bus(**bus_kwargs)
    request = can.Message(arbitration_id=0x600 + node_id, data=upload_request(0x1000, 0), is_extended_id=False)

    def round_trip() -> None:
        bus.send(request)
        while (reply := bus.recv(1.0)) is not None and reply.arbitration_id != 0x580 + node_id:
            pass
        assert reply is not None, "no SDO reply"

    bus.send(request)  # python-can-remote drops frames in its first ~20 ms
    bus.recv(0.1)
    try:
        return rate(round_trip, seconds)
    finally:
        bus.shutdown()


def dut_rates(dut: DeviceUnderTest, seconds: float) -> dict[str, float]:
    dut.responds()
    return {
        "canopen SdoClient.upload": rate(lambda: dut.node.sdo.upload(0x1000, 0), seconds),
        "DeviceUnderTest.read": rate(lambda: dut.read(0x1000, 0), seconds),
        "DeviceUnderTest.sdo_request": rate(lambda: dut.sdo_request(upload_request(0x1000, 0)), seconds),
    }


def main(seconds: float) -> None:
    profile = load_profile(PROFILE).profile
    twin = start_simulator(PROFILE)
    try:
        node_id = profile.bus.node_id
        figures: dict[str, list[float]] = {}
        for _ in range(3):
            figures.setdefault("raw python-can", []).append(raw_python_can(twin.bus_kwargs, node_id, seconds))
            log = FrameLog()
            network = connect(twin.bus_kwargs, "twin", log)
            for name, value in dut_rates(DeviceUnderTest(network, log, profile, node_id), seconds).items():
                figures.setdefault(name, []).append(value)
            disconnect(network)
        raw = statistics.median(figures["raw python-can"])
        for name, values in figures.items():
            median = statistics.median(values)
            print(f"{name:30s} {median:7.0f} round trips/s (median of 3)  {median / raw:6.1%} of raw python-can")
    finally:
        twin.stop()


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 2.0)
