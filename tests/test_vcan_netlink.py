"""rtnetlink on the user-space SocketCAN bus (encoder_conformance/vcan/preload_netlink.c), checked with programs
nobody here wrote: iproute2's ``ip`` shows and changes the bus's interfaces as a kernel vcan's, and a small C
program opens an interface as libsocketcan and C/C++ CANopen stacks do (RTM_GETLINK for the index
if_nametoindex gave, its transmit queue length). Interface state is shared by every process of the bus."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from encoder_conformance.vcan import add_interface, interfaces, start_hub, stop_hub, up

pytestmark = [
    pytest.mark.skipif(sys.platform != "linux", reason="the virtual CAN bus is Linux only"),
    pytest.mark.skipif(shutil.which("ip") is None,
                       reason="iproute2 is not installed (ip): apt-get install iproute2 (CI installs it)"),
]

WAIT_S = 10.0
PROBE_SOURCE = Path(__file__).parent / "data" / "rtnl_open.c"


@dataclass
class Bus:
    directory: Path
    env: dict[str, str]

    def ip(self, *args: str) -> subprocess.CompletedProcess[str]:
        """``ip ARGS`` under the preload library."""
        return subprocess.run(["ip", *args], env=self.env, capture_output=True, text=True, timeout=WAIT_S,
                              check=False)

    def show(self, name: str) -> dict[str, object]:
        """``ip -details -json link show NAME``: the interface as iproute2 decoded it."""
        done = self.ip("-details", "-json", "link", "show", name)
        assert done.returncode == 0, done.stderr
        (link,) = json.loads(done.stdout)
        assert isinstance(link, dict)
        return link


@pytest.fixture(scope="module")
def probe(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/data/rtnl_open.c, compiled."""
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        pytest.skip("no C compiler for tests/data/rtnl_open.c (apt-get install gcc; CI installs it)")
    target = tmp_path_factory.mktemp("rtnl-open") / "rtnl_open"
    subprocess.run([*compiler.split(), "-O1", "-Wall", "-o", str(target), str(PROBE_SOURCE)], check=True,
                   timeout=120)
    return target


@pytest.fixture
def bus(preload_library: Path) -> Iterator[Bus]:
    directory = Path(tempfile.mkdtemp(prefix="vcan-nl-"))  # short: AF_UNIX paths are limited to 107 bytes
    try:
        with up(["vcan0", "can0"], directory) as virtual:
            add_interface(directory, "vcan1", mtu=16, mode="wire")
            yield Bus(directory, virtual.env)
    finally:
        shutil.rmtree(directory, ignore_errors=True)


def test_ip_details_link_show_describes_a_vcan(bus):
    """``ip -details link show vcan0``: the kernel vcan's line (flags, mtu, qdisc, state, qlen, link/can, kind)."""
    done = bus.ip("-details", "link", "show", "vcan0")
    assert done.returncode == 0, done.stderr
    first, second, third = done.stdout.splitlines()[:3]
    index = interfaces(bus.directory)["vcan0"].ifindex
    assert first == (f"{index}: vcan0: <NOARP,UP,LOWER_UP> mtu 72 qdisc noqueue state UNKNOWN mode DEFAULT "
                     f"group default qlen 1000")
    assert second.split()[0] == "link/can"
    assert third.split()[0] == "vcan"
    link = bus.show("vcan0")
    assert (link["link_type"], link["mtu"], link["txqlen"], link["operstate"]) == ("can", 72, 1000, "UNKNOWN")
    assert link["linkinfo"] == {"info_kind": "vcan"}
    assert bus.show("vcan1")["mtu"] == 16  # a classic-CAN interface


def test_ip_link_show_lists_every_bus_interface(bus):
    """A dump lists each interface of the bus with its index, and nothing else (the host's are not the bus's)."""
    done = bus.ip("-json", "link", "show")
    assert done.returncode == 0, done.stderr
    listed = {link["ifname"]: link["ifindex"] for link in json.loads(done.stdout)}
    assert listed == {name: interface.ifindex for name, interface in interfaces(bus.directory).items()}
    addresses = bus.ip("address", "show")  # other dumps (addresses) are empty, never a hang
    assert addresses.returncode == 0, addresses.stderr
    assert "vcan0" in addresses.stdout


def test_txqueuelen_set_by_ip_is_seen_by_every_process(bus, probe):
    """``ip link set vcan0 txqueuelen N`` is kept in the interface's file: another ``ip``, the C program and
    this process see it."""
    for length in (500, 1000):
        done = bus.ip("link", "set", "vcan0", "txqueuelen", str(length))
        assert done.returncode == 0, done.stderr
        assert bus.show("vcan0")["txqlen"] == length
        assert interfaces(bus.directory)["vcan0"].txqlen == length
    assert bus.ip("link", "set", "can0", "txqueuelen", "10").returncode == 0
    (line,) = [line for line in _probe(bus, probe, "can0").splitlines() if line.startswith("link ")]
    assert "name=can0 " in line
    assert " txqlen=10 " in line


def test_down_and_up(bus):
    """Down: no UP flag, state DOWN, qdisc noop (netlink and SIOCGIFFLAGS); the MTU changes only while down (16
    or 72); up again as before."""
    assert bus.ip("link", "set", "vcan0", "down").returncode == 0
    link = bus.show("vcan0")
    assert (link["flags"], link["operstate"], link["qdisc"]) == (["NOARP"], "DOWN", "noop")
    assert not interfaces(bus.directory)["vcan0"].up
    assert _flags(bus, "vcan0") == 0x80  # IFF_NOARP alone
    assert bus.ip("link", "set", "vcan0", "mtu", "16").returncode == 0
    assert bus.ip("link", "set", "vcan0", "up").returncode == 0
    link = bus.show("vcan0")
    assert (link["flags"], link["operstate"], link["mtu"]) == (["NOARP", "UP", "LOWER_UP"], "UNKNOWN", 16)
    assert _flags(bus, "vcan0") == 0xC1  # IFF_UP | IFF_RUNNING | IFF_NOARP
    assert interfaces(bus.directory)["vcan0"].up


@pytest.mark.parametrize(("change", "error"), [
    (["mtu", "16"], "Device or resource busy"),  # vcan_change_mtu: not while up
    (["address", "00:11:22:33:44:55"], "Operation not supported"),  # a vcan has no hardware address
    (["type", "can", "bitrate", "500000"], "Operation not supported"),  # a vcan has no changelink
    (["name", "renamed"], "Device or resource busy"),  # dev_change_name: not while up
])
def test_unsupported_changes_are_refused_as_the_kernel_refuses_them(bus, change, error):
    done = bus.ip("link", "set", "vcan0", *change)
    assert (done.returncode, done.stderr.strip()) == (2, f"RTNETLINK answers: {error}")
    assert bus.show("vcan0")["mtu"] == 72


def test_refusals_while_down_and_of_interfaces_netlink_does_not_make(bus):
    """An MTU a vcan does not take (EINVAL), an interface that exists (EEXIST) or does not (the kernel's
    'Cannot find device'), a new one (interfaces are made by ``vcan up``, not netlink)."""
    assert bus.ip("link", "set", "vcan0", "down").returncode == 0
    assert bus.ip("link", "set", "vcan0", "mtu", "20").stderr.strip() == "RTNETLINK answers: Invalid argument"
    assert bus.ip("link", "add", "dev", "vcan0", "type", "vcan").stderr.strip() == "RTNETLINK answers: File exists"
    assert bus.ip("link", "set", "nosuch", "up").stderr.strip() == 'Cannot find device "nosuch"'
    made = bus.ip("link", "add", "dev", "vcan7", "type", "vcan")
    assert made.stderr.strip() == "RTNETLINK answers: Operation not supported"
    assert "vcan7" not in interfaces(bus.directory)


def test_a_c_program_opens_the_interface_as_libsocketcan_does(bus, probe):
    """RTM_GETLINK for if_nametoindex's index (type ARPHRD_CAN, MTU, IFLA_TXQLEN, kind vcan), a dump ending in
    NLMSG_DONE, ENODEV for an unknown index, answers from port 0 with the socket's own port and sequence, nothing
    left over; then the CAN socket binds."""
    lines = _probe(bus, probe, "vcan0").splitlines()
    index = interfaces(bus.directory)["vcan0"].ifindex
    assert lines[:3] == [f"nametoindex={index}", "bound family=16 portid-set=1",
                         f"link name=vcan0 index={index} type=280 flags=0x100c1 mtu=72 txqlen=1000 operstate=0 "
                         f"kind=vcan"]
    dumped = [line.split()[1] for line in lines if line.startswith("dump ")]
    by_index = sorted(interfaces(bus.directory).values(), key=lambda interface: interface.ifindex)
    assert dumped == [f"name={interface.name}" for interface in by_index]
    assert lines[-4:] == ["done", "error=-19", "left-over=0", "can-bind=0"]


def test_other_netlink_families_and_sockets_pass_through(bus):
    """Under the preload, a NETLINK_ROUTE socket is emulated (an AF_UNIX socket: in /proc/net/unix), a
    NETLINK_GENERIC one is the kernel's (in /proc/net/netlink)."""
    script = (
        "import os, socket\n"
        "route = socket.socket(socket.AF_NETLINK, socket.SOCK_RAW, socket.NETLINK_ROUTE)\n"
        "generic = socket.socket(socket.AF_NETLINK, socket.SOCK_RAW, 16)  # NETLINK_GENERIC\n"
        "route.bind((0, 0)), generic.bind((0, 0))  # (listed in /proc/net/netlink once bound)\n"
        "inode = lambda s: os.readlink(f'/proc/self/fd/{s.fileno()}')[8:-1]\n"
        "table = lambda name, column: {line.split()[column] for line in open(name).read().splitlines()[1:]}\n"
        "netlink, unix = table('/proc/net/netlink', -1), table('/proc/net/unix', 6)\n"
        "print(*(f'{inode(s) in netlink}/{inode(s) in unix}' for s in (route, generic)))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], env=bus.env, capture_output=True, text=True,
                          timeout=WAIT_S, check=True)
    assert done.stdout.split() == ["False/True", "True/False"]  # in netlink / in unix: route, generic


def _probe(bus: Bus, program: Path, name: str) -> str:
    """The output of tests/data/rtnl_open.c run on ``name`` under the bus."""
    done = subprocess.run([str(program), name], env=bus.env, capture_output=True, text=True, timeout=WAIT_S,
                          check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def _flags(bus: Bus, name: str) -> int:
    """SIOCGIFFLAGS as a program under the preload library reads it."""
    script = (
        "import fcntl, socket, struct, sys\n"
        "s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)\n"
        "ifr = fcntl.ioctl(s, 0x8913, struct.pack('16sh14x', sys.argv[1].encode(), 0))\n"
        "print(struct.unpack_from('16sh', ifr)[1])\n"
    )
    done = subprocess.run([sys.executable, "-c", script, name], env=bus.env, capture_output=True, text=True,
                          timeout=WAIT_S, check=True)
    return int(done.stdout) & 0xFFFF



def test_python_can_finds_the_interfaces_that_are_up(bus):
    """python-can's socketcan detection (``ip -json link list up``, link type can) lists the bus's interfaces
    that are up."""
    assert bus.ip("link", "set", "can0", "down").returncode == 0
    script = "import can; print(sorted(c['channel'] for c in can.detect_available_configs('socketcan')))"
    done = subprocess.run([sys.executable, "-c", script], env=bus.env, capture_output=True, text=True,
                          timeout=WAIT_S, check=True)
    assert done.stdout.strip() == "['vcan0', 'vcan1']"


def test_without_a_hub_an_interface_has_no_carrier(bus):
    """The hub stopped: the interfaces still exist (their files) but carry nothing, reported as the kernel reports
    a link without carrier; a hub started again brings the carrier back."""
    stop_hub(bus.directory)
    link = bus.show("vcan0")
    assert (link["flags"], link["operstate"]) == (["NO-CARRIER", "NOARP", "UP"], "DOWN")
    assert _flags(bus, "vcan0") == 0x81  # IFF_UP | IFF_NOARP
    start_hub(bus.directory, daemon=False)
    assert bus.show("vcan0")["flags"] == ["NOARP", "UP", "LOWER_UP"]
