"""The hub directory: its interfaces, its hub process, and the environment a program runs under.

A hub directory holds ``hub.sock`` (the hub's socket), ``hub.pid``, ``hub.log`` and ``if/<name>``, one file
per interface with ``"<ifindex> <mtu> <mode> <up> <txqlen>"``: what the preload library reads to answer
``if_nametoindex``, the ``SIOCGIF*`` ioctls and rtnetlink, and to let ``bind`` join. Creating that file is
``ip link add``; the hub needs no telling. The file is the interface's state shared by every process of the
bus: ``ip link set`` (netlink, preload_netlink.c) rewrites it under the directory's lock, as this module does.
ifindexes start at 1000, clear of the host's real interfaces.

The mode: ``vcan`` (default) flags every received frame MSG_DONTROUTE, sent on this host, as the kernel's
vcan does (python-can then marks every frame ``is_rx=False``); ``wire`` flags only a socket's own frames so,
as on a real CAN adapter, the other programs' frames arrive as from the bus (``is_rx=True``).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import selectors
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from encoder_conformance.deadline import Deadline
from encoder_conformance.errors import HubError
from encoder_conformance.vcan.build import library
from encoder_conformance.vcan.hub import HUB_SOCKET, PID_FILE
from encoder_conformance.vcan.protocol import CAN_MTU, CANFD_MTU

ENV_DIR = "ENCODER_CONFORMANCE_VCAN_DIR"
FIRST_IFINDEX = 1000
IF_NAMESIZE = 16
LOG_FILE = "hub.log"
MODES = ("vcan", "wire")
DEFAULT_TXQLEN = 1000  # a vcan's qlen as the kernel reports it


def default_directory() -> Path:
    """``$ENCODER_CONFORMANCE_VCAN_DIR``, else a per-user folder in ``$XDG_RUNTIME_DIR`` or the temporary folder."""
    named = os.environ.get(ENV_DIR)
    if named:
        return Path(named)
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime and os.access(runtime, os.W_OK):
        return Path(runtime) / "encoder-conformance-vcan"
    return Path(tempfile.gettempdir()) / f"encoder-conformance-vcan-{os.getuid()}"


@contextlib.contextmanager
def _locked(directory: Path) -> Iterator[None]:
    directory.mkdir(parents=True, exist_ok=True)
    with open(directory / ".lock", "a+b") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield


def check_name(name: str) -> None:
    """ValueError unless ``name`` can be an interface name. For programs under the preload library, an
    interface of the hub hides a host interface of the same name (a real vcan0 or can0)."""
    if not name or len(name.encode()) >= IF_NAMESIZE or "/" in name or name.startswith(".") or any(
            c.isspace() or c == ":" for c in name):
        raise ValueError(f"not a usable interface name: {name!r} (1 to 15 characters, no '/', ':' or blanks)")


@dataclass(frozen=True)
class Interface:
    name: str
    ifindex: int
    mtu: int = CANFD_MTU
    mode: str = "vcan"
    up: bool = True
    txqlen: int = DEFAULT_TXQLEN

    def line(self) -> str:
        """The interface file's content."""
        return f"{self.ifindex} {self.mtu} {self.mode} {int(self.up)} {self.txqlen}\n"


def _parse(name: str, text: str) -> Interface:
    """An interface file: ``ifindex mtu mode`` and, written since netlink is answered, ``up txqlen``."""
    fields = text.split()
    if len(fields) not in (3, 5):
        raise ValueError(f"not an interface file: {text!r}")
    up, txqlen = (bool(int(fields[3])), int(fields[4])) if len(fields) == 5 else (True, DEFAULT_TXQLEN)
    return Interface(name, int(fields[0]), int(fields[1]), fields[2], up, txqlen)


def interfaces(directory: Path) -> dict[str, Interface]:
    """Every interface of the directory by name."""
    found = {}
    folder = Path(directory) / "if"
    for path in sorted(folder.iterdir()) if folder.is_dir() else []:
        with contextlib.suppress(OSError, ValueError):
            found[path.name] = _parse(path.name, path.read_text(encoding="ascii"))
    return found


def add_interface(directory: Path, name: str, mtu: int = CANFD_MTU, mode: str = "vcan") -> Interface:
    """Create interface ``name`` (CAN FD capable with mtu 72, classic only with 16; ``mode`` vcan or wire).
    An interface that exists keeps its ifindex, up/down state and txqlen (mtu and mode are updated)."""
    check_name(name)
    if mtu not in (CAN_MTU, CANFD_MTU):
        raise ValueError(f"mtu must be {CAN_MTU} (classic CAN) or {CANFD_MTU} (CAN FD), not {mtu}")
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, not {mode!r}")
    directory = Path(directory)
    with _locked(directory):
        known = interfaces(directory)
        taken = {interface.ifindex for interface in known.values()}
        ifindex = known[name].ifindex if name in known else next(
            i for i in range(FIRST_IFINDEX, FIRST_IFINDEX + len(taken) + 1) if i not in taken)
        interface = Interface(name, ifindex, mtu, mode)
        if name in known:
            interface = Interface(name, ifindex, mtu, mode, known[name].up, known[name].txqlen)
        folder = directory / "if"
        folder.mkdir(exist_ok=True)
        partial = folder / f".{name}.part"
        partial.write_text(interface.line(), encoding="ascii")
        os.replace(partial, folder / name)
    return interface


def remove_interface(directory: Path, name: str) -> bool:
    """Delete interface ``name`` (sockets bound to it keep working until they close); whether it existed."""
    with _locked(Path(directory)):
        try:
            (Path(directory) / "if" / name).unlink()
        except FileNotFoundError:
            return False
    return True


def hub_pid(directory: Path) -> int | None:
    """The pid of the hub serving ``directory``, or None if none answers."""
    path = Path(directory) / HUB_SOCKET
    probe = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    try:
        probe.settimeout(2.0)
        probe.connect(str(path))
    except OSError:
        return None
    finally:
        probe.close()
    with contextlib.suppress(OSError, ValueError):
        return int((Path(directory) / PID_FILE).read_text(encoding="utf-8"))
    return None


_children: dict[int, subprocess.Popen[bytes]] = {}


def start_hub(directory: Path, *, daemon: bool = True, timeout: float = 10.0) -> int:
    """Start the directory's hub unless one runs; its pid. ``daemon``: the hub outlives this process (init
    adopts it); otherwise it is this process's child, to be ended by ``stop_hub``."""
    directory = Path(directory)
    with _locked(directory):
        running = hub_pid(directory)
        if running is not None:
            return running
        env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", ENV_DIR)}
        source_root = str(Path(__file__).resolve().parents[2])  # importable from "/" also when not installed
        env["PYTHONPATH"] = os.pathsep.join(p for p in (source_root, env.get("PYTHONPATH")) if p)
        command = [sys.executable, "-m", "encoder_conformance.vcan", "hub", *(["--daemon"] if daemon else []),
                   str(directory)]
        with open(directory / LOG_FILE, "ab") as log:
            process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log,
                                       env=env, start_new_session=True, cwd="/")
        assert process.stdout is not None
        line = _first_line(process.stdout, timeout)
        process.stdout.close()
        if not line.startswith(b"ready "):
            process.kill()
            process.wait()
            tail = (directory / LOG_FILE).read_text(encoding="utf-8", errors="replace").strip().splitlines()[-5:]
            raise HubError(f"the vcan hub for {directory} did not start: {' | '.join(tail) or 'no message'}")
        pid = int(line.split()[1])
        if daemon:
            process.wait()  # the parent that forked the hub away
        else:
            _children[pid] = process
        return pid


def _first_line(stream: IO[bytes], timeout: float) -> bytes:
    selector = selectors.DefaultSelector()
    selector.register(stream, selectors.EVENT_READ)
    try:
        return stream.readline() if selector.select(timeout) else b""
    finally:
        selector.close()


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    with contextlib.suppress(OSError):  # a zombie nobody reaps yet (a container without an init)
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    return False


def stop_hub(directory: Path, *, timeout: float = 5.0) -> bool:
    """End the directory's hub (SIGTERM, SIGKILL after ``timeout``); whether one was running."""
    pid = hub_pid(directory)
    if pid is None:
        return False
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGTERM)
    child = _children.pop(pid, None)
    if child is not None:
        try:
            child.wait(timeout)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
        return True
    deadline = Deadline(timeout)
    while not _gone(pid):
        if deadline.expired():
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
            break
        time.sleep(0.02)
    return True


def environment(directory: Path, base: Mapping[str, str] | None = None) -> dict[str, str]:
    """``base`` (default: this process's environment) with the preload library and the hub directory set."""
    env = dict(os.environ if base is None else base)
    lib = str(library())
    preload = [p for p in env.get("LD_PRELOAD", "").replace(":", " ").split() if p and p != lib]
    env["LD_PRELOAD"] = ":".join([lib, *preload])
    env[ENV_DIR] = str(Path(directory).resolve())
    return env


@dataclass
class VirtualCan:
    """A running hub with its interfaces; ``env`` is what a program needs to join them.

    >>> with up(["vcan0"], directory) as bus:
    ...     subprocess.run(["candump", "vcan0"], env=bus.env)
    """

    directory: Path
    names: list[str]
    daemon: bool = False
    env: dict[str, str] = field(default_factory=dict)

    def stop(self) -> None:
        """End the hub (the interface files stay for the next hub)."""
        stop_hub(self.directory)

    def __enter__(self) -> VirtualCan:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def up(names: list[str], directory: Path | None = None, *, mtu: int = CANFD_MTU, mode: str = "vcan",
       daemon: bool = False) -> VirtualCan:
    """Create the interfaces and start the hub (or use the running one): the bus, ready to join."""
    directory = Path(directory or default_directory())
    env = environment(directory)  # builds the library before anything runs
    for name in names:
        add_interface(directory, name, mtu, mode)
    start_hub(directory, daemon=daemon)
    return VirtualCan(directory, list(names), daemon, env)


def down(directory: Path | None = None, names: list[str] | None = None) -> bool:
    """Delete the named interfaces, or with none named stop the hub and delete every interface; whether
    anything was there."""
    directory = Path(directory or default_directory())
    if names:
        return any([remove_interface(directory, name) for name in names])
    stopped = stop_hub(directory)
    removed = [remove_interface(directory, name) for name in interfaces(directory)]
    return stopped or any(removed)
