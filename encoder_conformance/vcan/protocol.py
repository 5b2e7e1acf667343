"""The wire between preload.c and the hub, and the kernel's CAN_RAW receive rules the hub applies.

Kept in step with the ``VC_*`` definitions and structs at the top of ``preload.c`` (native byte order,
one AF_UNIX SOCK_SEQPACKET message each):

- to the hub: a CAN frame (16 bytes) or CAN FD frame (72 bytes) for the bound interface; a control
  message ``CONTROL`` + filters + one pad byte (its odd length tells it from a frame); or ``TX_HEADER`` +
  frame + one pad byte, a frame for another interface than the bound one (``sendto``);
- from the hub: ``RX_HEADER`` + frame; ``RX_HEADER`` alone with ``ACK`` answers ``JOIN``.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

MAGIC = 0x4E414356  # "VCAN"
ACK = 0x80000000  # RX_HEADER flags: the answer to JOIN
OWN = 0x1  # RX_HEADER flags: the receiver sent this frame (MSG_CONFIRM)
JOIN, OPTS, TX = 1, 2, 3

#: magic, flags, ifindex, drops, seconds, nanoseconds
RX_HEADER = struct.Struct("=IIiIqq")
#: magic, type, ifindex, mtu, loopback, recv_own, fd_frames, join_filters, err_mask, rcvbuf, nfilters
CONTROL = struct.Struct("=IIiIIIIIIII")
#: magic, type, ifindex (then the frame and a pad byte)
TX_HEADER = struct.Struct("=IIi")
FILTER = struct.Struct("=II")

CAN_MTU, CANFD_MTU = 16, 72
CAN_EFF_FLAG, CAN_RTR_FLAG, CAN_ERR_FLAG = 0x80000000, 0x40000000, 0x20000000
CAN_INV_FILTER = CAN_ERR_FLAG
CAN_SFF_MASK, CAN_ERR_MASK = 0x7FF, 0x1FFFFFFF
FRAME_ID = struct.Struct("=I")


def compile_filter(can_id: int, mask: int) -> tuple[str, int, int]:
    """One CAN_RAW_FILTER entry as the kernel registers it (net/can/af_can.c ``find_rcv_list``):
    ``("err", mask, 0)``, ``("inv", id, mask)`` or ``("fil", id, mask)``."""
    if mask & CAN_ERR_FLAG:
        return ("err", mask & CAN_ERR_MASK, 0)
    inverted = can_id & CAN_INV_FILTER
    if mask & CAN_EFF_FLAG and not can_id & CAN_EFF_FLAG:
        mask &= CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG  # an SFF-only filter
    return ("inv" if inverted else "fil", can_id & mask, mask)


@dataclass
class Options:
    """A member socket's CAN_RAW options (defaults: the kernel's for a new socket)."""

    ifindex: int = 0
    mtu: int = CANFD_MTU
    loopback: bool = True
    recv_own: bool = False
    fd_frames: bool = False
    join_filters: bool = False
    err_mask: int = 0
    rcvbuf: int = 0
    filters: list[tuple[str, int, int]] = field(default_factory=lambda: [compile_filter(0, 0)])
    passes_all: bool = True  # the default filter: every data frame, no test needed

    @classmethod
    def parse(cls, message: bytes) -> tuple[int, Options]:
        """The control message's type and the options it carries; ValueError if malformed."""
        if len(message) < CONTROL.size + 1 or len(message) % 2 == 0:
            raise ValueError("not a control message")
        magic, kind, ifindex, mtu, loopback, own, fd, join, err_mask, rcvbuf, count = CONTROL.unpack_from(message)
        if magic != MAGIC or len(message) != CONTROL.size + FILTER.size * count + 1:
            raise ValueError("malformed control message")
        raw = [FILTER.unpack_from(message, CONTROL.size + i * FILTER.size) for i in range(count)]
        filters = [compile_filter(can_id, mask) for can_id, mask in raw]
        options = cls(ifindex, mtu, bool(loopback), bool(own), bool(fd), bool(join), err_mask, rcvbuf, filters,
                      passes_all=not join and any(f == ("fil", 0, 0) for f in filters))
        return kind, options

    def accepts(self, can_id: int) -> bool:
        """Whether a frame with this can_id passes the socket's filters (net/can/af_can.c ``can_rcv_filter``,
        net/can/raw.c ``raw_rcv`` for CAN_RAW_JOIN_FILTERS)."""
        if can_id & CAN_ERR_FLAG:
            return bool(can_id & self.err_mask) or any(k == "err" and can_id & m for k, m, _ in self.filters)
        if self.passes_all:
            return True
        hits = 0
        for kind, fid, mask in self.filters:
            if kind == "err":
                continue
            hit = (can_id & mask) == fid if kind == "fil" else (can_id & mask) != fid
            if hit and not self.join_filters:
                return True
            hits += hit
        return self.join_filters and bool(self.filters) and hits == len(self.filters)
