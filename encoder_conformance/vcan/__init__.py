"""A user-space SocketCAN bus: unmodified SocketCAN programs talk to each other where vcan cannot be loaded.

CI runners are containers without the kernel's CAN modules. Programs run with ``LD_PRELOAD`` of a small C
library (``preload.c``, compiled at first use by ``build.py``) get CAN_RAW sockets that are AF_UNIX
connections to a hub process (``hub.py``), which relays every frame among the sockets of an interface as
the kernel's vcan does. Checked with can-utils (cansend, candump, cangen), CPython's socket module with
python-can's ``socketcan`` interface and the ``canopen`` library, and CANopenLinux (epoll, threads).

What is emulated: ``socket(PF_CAN, SOCK_RAW, CAN_RAW)``, ``bind`` to an interface or to any (ifindex 0),
``if_nametoindex``/``if_indextoname`` and the ``SIOCGIFINDEX``/``SIOCGIFNAME``/``SIOCGIFMTU``/
``SIOCGIFFLAGS``/``SIOCGIFTXQLEN``/``SIOCGSTAMP[NS]`` ioctls, rtnetlink about the interfaces
(``preload_netlink.c``: ``ip link show``/``ip link set`` up, down, txqueuelen, mtu; the state kept in the
interface files, ``preload_links.c``, shared by every process), the CAN_RAW options (filters with the
kernel's rules including inverted and SFF-only filters, error mask, loopback, own messages flagged
MSG_CONFIRM, CAN FD frames, joined filters), receive timestamps (SO_TIMESTAMP, SO_TIMESTAMPNS, software
SO_TIMESTAMPING), drop counts (SO_RXQ_OVFL), SO_RCVBUF sizing the queue, ``sockaddr_can`` in
``recvmsg``/``recvfrom``/``getsockname``, ``sendto`` another interface, CAN and CAN FD frames (16 and 72
bytes, sizes checked as the kernel does), read/write/recv*/send*/poll/select/epoll on the socket, and
dup/dup2/dup3/F_DUPFD of it. Frames are stamped when the sender hands them to its socket. Several interfaces
per hub; a member that dies is removed, the others go on; a member that stops reading loses frames
(counted), the others do not.

What is NOT emulated: bus timing of any kind (bit rate, bit timing, arbitration: frames are delivered in the
order the hub reads them and as fast as it can, with no bus load limit), errors on the bus (no error frames
are generated, no error counters, error-passive or bus-off states, no retransmission or missing ACK: a frame
nobody reads is not an error), hardware timestamps, CAN XL (CAN_RAW_XL_FRAMES is refused), the other CAN
protocols (CAN_BCM, ISO-TP, J1939: ``socket`` fails with EAFNOSUPPORT as without CAN in the kernel, so
python-can's ``send_periodic`` on socketcan raises OSError, and with it canopen's SYNC producer, periodic
PDOs and guarding producer), the ``can`` link kind with a bit rate, ``ip link add``/``del`` (README: what
netlink answers and refuses), a down interface's silence (it still carries frames), sending on an unbound
socket, a CAN socket inherited across ``exec`` (the new program sees the AF_UNIX socket), and statically
linked or Go programs (they make system calls without glibc, where LD_PRELOAD cannot reach). The hub is a
program like the others: when it stops, the interfaces are gone (bind fails with ENETDOWN; a bound socket's
next read fails with ENETDOWN, then it never becomes readable again, like a kernel socket whose interface
was deleted, and its writes fail with ENETDOWN; a hub started again serves new sockets only).

The interface's mode: ``vcan`` (default) flags every received frame MSG_DONTROUTE, sent on this host, as
the kernel's vcan does, so python-can marks every frame ``is_rx=False``; ``wire`` flags only a socket's
own frames, so the other programs' frames arrive as from a real bus (``is_rx=True``), which is what a
tester that tells the device's frames from its own by ``is_rx`` needs.

Use: ``runtime.up(["vcan0"], directory)`` (tests, ``with`` closes it) gives the environment for the
programs; from a shell, ``command.py``: ``vcan up vcan0``, ``vcan run -- candump vcan0``, ``vcan down``.
"""

from encoder_conformance.vcan.build import BuildError, library
from encoder_conformance.vcan.runtime import (
    ENV_DIR,
    HubError,
    Interface,
    VirtualCan,
    add_interface,
    default_directory,
    down,
    environment,
    hub_pid,
    interfaces,
    remove_interface,
    start_hub,
    stop_hub,
    up,
)

__all__ = [
    "ENV_DIR",
    "BuildError",
    "HubError",
    "Interface",
    "VirtualCan",
    "add_interface",
    "default_directory",
    "down",
    "environment",
    "hub_pid",
    "interfaces",
    "library",
    "remove_interface",
    "start_hub",
    "stop_hub",
    "up",
]
