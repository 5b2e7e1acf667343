"""A failing fuzz example as something to replay: the bus as it happened and the requests as a script.

The frames are the example's window as the tester logged them (both directions); the requests are
also given in candump -L form (``canplayer -I FILE`` sends them) and as a python-can snippet.
"""

from __future__ import annotations

from collections.abc import Sequence

import can

from encoder_conformance.dut.link.frames import format_frames
from encoder_conformance.fuzz.strategies import Request


def candump_lines(cob_id: int, requests: Sequence[Request], channel: str = "can0") -> str:
    """The requests in candump -L log form (one frame per line, 10 ms apart)."""
    return "\n".join(f"({n * 0.01:.6f}) {channel} {cob_id:03X}#{r.frame.hex().upper()}" for n, r in enumerate(requests))


def python_snippet(cob_id: int, requests: Sequence[Request]) -> str:
    """Sends the requests one by one and prints what comes back within 100 ms of each."""
    frames = ",\n    ".join(f'"{r.frame.hex(" ").upper()}"' for r in requests)
    return (
        "import can\n"
        "bus = can.Bus()  # python-can's configuration, or interface=..., channel=..., bitrate=...\n"
        f"for data in [\n    {frames},\n]:\n"
        f"    bus.send(can.Message(arbitration_id=0x{cob_id:03X}, data=bytes.fromhex(data), is_extended_id=False))\n"
        "    while (reply := bus.recv(0.1)) is not None:\n"
        "        print(reply)\n"
    )


def describe(cob_id: int, requests: Sequence[Request], window: list[can.Message], before: list[can.Message],
             how_to_rerun: str) -> str:
    """The report text of a failing example."""
    parts = [f"failing example: {len(requests)} request frames to {cob_id:03X}h (the example; an abort transfer "
             "request where it may have opened one; the read of 1000h that ends every example)",
             "bus during the example:", format_frames(window)]
    if before:
        parts += ["bus during the example before it (a late reply to it shows in this one):", format_frames(before)]
    parts += ["requests (candump -L; canplayer -I FILE):", candump_lines(cob_id, requests),
              "the same with python-can:", python_snippet(cob_id, requests), how_to_rerun]
    return "\n".join(parts)
