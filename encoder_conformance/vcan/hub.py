"""The hub: relays CAN frames among the sockets of each virtual interface, as the kernel's vcan does.

One hub serves every interface of its directory (``$DIR/hub.sock``); a member is one CAN_RAW socket of a
program running under the preload library. Each frame a member sends goes to every other member of its
interface and to the members bound to any interface (ifindex 0) whose CAN_RAW filters accept it; back to
the sender only with CAN_RAW_RECV_OWN_MSGS (flagged MSG_CONFIRM by the library), to nobody when the
sender turned CAN_RAW_LOOPBACK off, and CAN FD frames only to members that enabled CAN_RAW_FD_FRAMES.
The frame is stamped with the time the sender handed it to its socket (the kernel's stamp of the AF_UNIX
message, the hub's clock where the kernel gives none). A member whose queue is full loses the frame and
its drop count grows (reported as SO_RXQ_OVFL); a member that closes or dies is removed, the others go on.

``python -m encoder_conformance.vcan hub [--daemon] DIR`` serves until SIGTERM or SIGINT and prints
``ready PID`` once it accepts members (``--daemon``: in a process of its own that init adopts).
"""

from __future__ import annotations

import contextlib
import os
import resource
import selectors
import signal
import socket
import struct
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from encoder_conformance.errors import HubStop
from encoder_conformance.vcan.protocol import (
    ACK,
    CAN_MTU,
    CANFD_MTU,
    FRAME_ID,
    JOIN,
    MAGIC,
    OPTS,
    OWN,
    RX_HEADER,
    TX,
    TX_HEADER,
    Options,
)

HUB_SOCKET = "hub.sock"
PID_FILE = "hub.pid"
SO_TIMESTAMPNS = 35
SCM_TIMESTAMPNS = SO_TIMESTAMPNS
SO_SNDBUFFORCE = 32
STAMP = struct.Struct("=qq")
#: the kernel's default socket receive buffer (net.core.rmem_default), for a member that set no SO_RCVBUF
DEFAULT_RCVBUF = 212992
#: an AF_UNIX message of one frame takes about 766 bytes of buffer, a CAN skb about 446 (measured): the
#: member's queue is sized to hold as many frames as its CAN_RAW socket would
UNIX_PER_CAN_SKB = 766 / 446
BURST = 64  # messages read from one member before the others get their turn
MAX_MESSAGE = 8192  # the largest control message: 44 + 512 filters of 8 + 1 bytes


@dataclass(eq=False)
class Member:
    sock: socket.socket
    options: Options = field(default_factory=Options)
    joined: bool = False
    drops: int = 0


class Hub:
    """The relay of one hub directory; ``serve`` runs it in the calling thread."""

    def __init__(self, directory: Path) -> None:
        self.directory = Path(directory)
        self.selector = selectors.DefaultSelector()
        self.members: dict[int, Member] = {}
        self.groups: dict[int, list[Member]] = {}  # ifindex -> joined members; 0: bound to any interface
        self.listener: socket.socket | None = None
        self.frames = 0

    @property
    def path(self) -> Path:
        return self.directory / HUB_SOCKET

    def open(self) -> None:
        """Listen on ``DIR/hub.sock`` (a stale socket left by a dead hub is replaced)."""
        self.directory.mkdir(parents=True, exist_ok=True)
        if len(os.fsencode(self.path)) >= 108:
            raise OSError(f"hub socket path too long for AF_UNIX (max 107 bytes): {self.path}")
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        with contextlib.suppress(FileNotFoundError):
            probe = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
            try:
                probe.connect(str(self.path))
            except ConnectionRefusedError:
                self.path.unlink()  # nobody listens: a dead hub's socket
            else:
                listener.close()
                raise OSError(f"a hub already serves {self.directory}")
            finally:
                probe.close()
        listener.bind(str(self.path))
        listener.listen(128)
        listener.setblocking(False)
        self.listener = listener
        self.selector.register(listener, selectors.EVENT_READ, None)
        (self.directory / PID_FILE).write_text(f"{os.getpid()}\n", encoding="utf-8")

    def close(self) -> None:
        for member in list(self.members.values()):
            self._remove(member)
        if self.listener is not None:
            self.selector.unregister(self.listener)
            self.listener.close()
            self.listener = None
            pid_file = self.directory / PID_FILE
            with contextlib.suppress(OSError):
                if pid_file.read_text(encoding="utf-8").strip() == str(os.getpid()):
                    pid_file.unlink()
                    self.path.unlink()
        self.selector.close()

    def serve(self, timeout: float | None = None) -> None:
        """Relay until ``HubStop`` (or, with ``timeout``, until that long passed without traffic)."""
        while True:
            events = self.selector.select(timeout)
            if not events and timeout is not None:
                return
            for key, _ in events:
                if key.data is None:
                    self._accept()
                else:
                    self._read(key.data)

    def _accept(self) -> None:
        assert self.listener is not None
        while True:
            try:
                sock, _ = self.listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # out of file descriptors: the newcomer waits in the backlog
                return
            sock.setblocking(False)
            sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
            member = Member(sock)
            self.members[sock.fileno()] = member
            self.selector.register(sock, selectors.EVENT_READ, member)

    def _remove(self, member: Member) -> None:
        if self.members.pop(member.sock.fileno(), None) is None:
            return
        self._leave(member)
        self.selector.unregister(member.sock)
        member.sock.close()

    def _leave(self, member: Member) -> None:
        if member.joined:
            group = self.groups.get(member.options.ifindex, [])
            if member in group:
                group.remove(member)
            member.joined = False

    def _read(self, member: Member) -> None:
        for _ in range(BURST):
            try:
                data, ancillary, _flags, _ = member.sock.recvmsg(MAX_MESSAGE, 64)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                self._remove(member)
                return
            if not data:
                self._remove(member)
                return
            stamp = None
            for level, kind, payload in ancillary:
                if level == socket.SOL_SOCKET and kind == SCM_TIMESTAMPNS and len(payload) >= STAMP.size:
                    stamp = STAMP.unpack_from(payload)
            if stamp is None:
                stamp = divmod(time.time_ns(), 1_000_000_000)
            size = len(data)
            if size in (CAN_MTU, CANFD_MTU):
                options = member.options
                classic_or_allowed = size == CAN_MTU or (options.fd_frames and options.mtu >= size)
                if member.joined and options.ifindex and classic_or_allowed:
                    self._deliver(member, options.ifindex, data, stamp)
            elif size % 2:
                self._control(member, data, stamp)
            if member.sock.fileno() not in self.members:
                return

    def _control(self, member: Member, data: bytes, stamp: tuple[int, int]) -> None:
        magic, kind, ifindex = TX_HEADER.unpack_from(data)
        if magic != MAGIC:
            return
        if kind == TX:
            frame = data[TX_HEADER.size:-1]
            if member.joined and ifindex and len(frame) in (CAN_MTU, CANFD_MTU):
                self._deliver(member, ifindex, frame, stamp)
            return
        try:
            kind, options = Options.parse(data)
        except ValueError:
            return
        if kind not in (JOIN, OPTS):
            return
        self._leave(member)
        member.options = options
        self._size_queue(member)
        if kind == JOIN:
            try:
                member.sock.send(RX_HEADER.pack(MAGIC, ACK, options.ifindex, 0, 0, 0))
            except OSError:
                self._remove(member)
                return
        self.groups.setdefault(options.ifindex, []).append(member)
        member.joined = True

    def _size_queue(self, member: Member) -> None:
        """Let the member's queue hold as many frames as a CAN_RAW socket with its receive buffer would."""
        want = int(max(member.options.rcvbuf, DEFAULT_RCVBUF) * UNIX_PER_CAN_SKB) // 2  # the kernel doubles it
        for option in (SO_SNDBUFFORCE, socket.SO_SNDBUF):
            try:
                member.sock.setsockopt(socket.SOL_SOCKET, option, want)
                return
            except OSError:
                continue

    def _deliver(self, sender: Member, ifindex: int, frame: bytes, stamp: tuple[int, int]) -> None:
        if not sender.options.loopback:
            return  # vcan: without local loopback nobody on this host hears the frame
        self.frames += 1
        (can_id,) = FRAME_ID.unpack_from(frame)
        is_fd = len(frame) == CANFD_MTU
        plain = b""
        dead = []
        recipients = self.groups.get(ifindex, [])
        if ifindex and self.groups.get(0):
            recipients = recipients + self.groups[0]
        for member in recipients:
            options = member.options
            own = member is sender
            if (own and not options.recv_own) or (is_fd and not options.fd_frames) or not options.accepts(can_id):
                continue
            if own or member.drops:
                message = RX_HEADER.pack(MAGIC, OWN if own else 0, ifindex, member.drops, *stamp) + frame
            else:
                plain = plain or RX_HEADER.pack(MAGIC, 0, ifindex, 0, *stamp) + frame
                message = plain
            try:
                member.sock.send(message)
            except (BlockingIOError, InterruptedError):
                member.drops = (member.drops + 1) & 0xFFFFFFFF
            except OSError:
                dead.append(member)
        for member in dead:
            self._remove(member)


def _stop(signum: int, frame: object) -> None:
    raise HubStop


def _raise_file_limit() -> None:
    with contextlib.suppress(ValueError, OSError):
        soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
        if soft != hard:
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))


def main(argv: list[str]) -> int:
    daemon = argv[:1] == ["--daemon"]
    argv = argv[1:] if daemon else argv
    if len(argv) != 1:
        print("usage: python -m encoder_conformance.vcan hub [--daemon] DIR", file=sys.stderr)
        return 2
    if daemon and os.fork():  # the starter reaps this parent at once; init adopts the hub
        os._exit(0)
    signal.signal(signal.SIGTERM, _stop)
    signal.signal(signal.SIGINT, _stop)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    _raise_file_limit()
    hub = Hub(Path(argv[0]))
    try:
        hub.open()
    except OSError as error:
        print(f"vcan hub: {error}", file=sys.stderr)
        return 1
    print(f"ready {os.getpid()}", flush=True)
    devnull = os.open(os.devnull, os.O_WRONLY)  # let the starter's pipe go; fd 1 stays taken
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    try:
        hub.serve()
    except HubStop:
        pass
    finally:
        hub.close()
    return 0
