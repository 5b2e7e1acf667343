"""How far a device's later SDO round trips spread beyond the p99 measured at the start of a run: the figure
``dut/link/windows.py``'s FACTOR rests on. Not collected by pytest; run
``python tests/perf_answer_spread.py [PROFILE ...] [--busy] [--later N]``.

Per profile and round: the start measurement (``measure_sdo``, 30 round trips), then N later round trips; printed:
the start p99, the later p99 and max, and max / start p99 (the factor a window needs to hold every later answer).
"""

from __future__ import annotations

import sys
import time

from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link.answer_times import measure_sdo
from encoder_conformance.dut.link.connection import connect, disconnect
from encoder_conformance.dut.link.frames import FrameLog
from encoder_conformance.dut.sdo.sdo_frames import upload_request
from encoder_conformance.models.timing import percentile
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.runs.host_load import busy_process
from encoder_conformance.sim.process import start_simulator

ROUNDS = 3


def spread(profile_id: str, later: int) -> list[float]:
    """Max / start p99 of each round against the profile's twin."""
    profile = load_profile(profile_id).profile
    twin = start_simulator(profile_id)
    ratios = []
    try:
        for _ in range(ROUNDS):
            log = FrameLog()
            network = connect(twin.bus_kwargs, "twin", log)
            dut = DeviceUnderTest(network, log, profile, profile.bus.node_id)
            dut.responds()
            start = measure_sdo(dut)
            assert start is not None
            times = []
            for _ in range(later):
                began = time.perf_counter()
                assert dut.sdo_request(upload_request(0x1000, 0)) is not None
                times.append((time.perf_counter() - began) * 1000)
            ratio = max(times) / start.p99_ms
            ratios.append(ratio)
            print(f"{profile_id:28s} start p50 {start.p50_ms:5.2f} p99 {start.p99_ms:5.2f} max {start.max_ms:5.2f} "
                  f"host {start.host_late_ms:5.2f} | later p99 {percentile(times, 0.99):6.2f} max {max(times):6.2f} "
                  f"ms | max/start p99 {ratio:5.1f}", flush=True)
            disconnect(network)
    finally:
        twin.stop()
    return ratios


def main(args: list[str]) -> None:
    busy = "--busy" in args
    later = int(args[args.index("--later") + 1]) if "--later" in args else 1000
    profiles = [a for a in args if not a.startswith("--") and not a.isdigit()] or ["wachendorff-wdga-mt"]
    with busy_process(busy):
        ratios = [r for p in profiles for r in spread(p, later)]
    print(f"{'busy' if busy else 'idle'}: max/start p99 over {len(ratios)} rounds: worst {max(ratios):.1f}, "
          f"median {sorted(ratios)[len(ratios) // 2]:.1f}")


if __name__ == "__main__":
    main(sys.argv[1:])
