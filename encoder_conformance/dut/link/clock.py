"""Which clock stamps the frames a timing verdict is judged on.

python-can's ``Message.timestamp`` comes from the interface: adapters with their own clock stamp frames
in hardware as they are received (PCAN, Kvaser, Vector, IXXAT, ...), socketcan in the kernel, and the
host-side interfaces (virtual, remote, serial) with ``time.time()`` of some process. The tester's own
frames (a SYNC it sends) are stamped by the FrameLog with the host clock just before ``send``. A report
must say which clock judged: host timestamps carry the host's scheduling latency, hardware ones do not.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

#: interfaces whose driver stamps received frames with the adapter's own clock
HARDWARE_TIMESTAMPS = frozenset({"pcan", "kvaser", "vector", "ixxat", "neovi", "nican", "systec", "etas",
                                 "gs_usb", "cantact", "canalystii", "nixnet", "seeedstudio"})
#: interfaces whose frames carry the host's clock (the sending or receiving process's time.time())
HOST_STAMPED = {
    "virtual": "python-can virtual interface: time.time() of the sending process at send",
    "remote": "python-can-remote: the timestamp of the server's bus (host clock where that bus is virtual)",
    "udp_multicast": "python-can udp_multicast: time.time() of the sending process",
    "slcan": "slcan: time.time() at receive (the adapter's own stamp is not used)",
    "serial": "serial: time.time() at receive",
    "socketcan": "socketcan: the kernel's receive time (software, on the host)",
}


@dataclass(frozen=True)
class FrameClock:
    """How received frames are stamped, in a sentence for the report; ``hardware`` where the adapter stamps."""

    description: str
    hardware: bool

    #: the tester's own frames (SYNC, NMT, SDO requests) are always stamped on the host
    own_frames = "the tester's own frames: host clock, time.time() just before send"

    def describe(self, own_frames_too: bool = False) -> str:
        text = self.description if self.hardware else f"host clock: {self.description}"
        if not self.hardware:
            text += " (the interface gives no hardware timestamps)"
        return f"{text}; {self.own_frames}" if own_frames_too else text


def frame_clock(bus_kwargs: dict[str, Any], simulated: bool = False) -> FrameClock:
    """The clock of ``Message.timestamp`` for a bus opened with ``bus_kwargs`` (``simulated``: the built-in
    twin behind python-can-remote or a virtual channel)."""
    interface = str(bus_kwargs.get("interface") or "")
    if simulated:
        return FrameClock("the simulated twin stamps each frame with time.time() at send (python-can "
                          f"{interface or 'virtual'} interface, same host as the tester)", hardware=False)
    if interface in HARDWARE_TIMESTAMPS:
        return FrameClock(f"interface timestamps of {interface} (the adapter's clock at receive)", hardware=True)
    return FrameClock(HOST_STAMPED.get(interface, f"{interface or 'unknown'} interface: its Message.timestamp, "
                                                  "assumed host time"), hardware=False)
