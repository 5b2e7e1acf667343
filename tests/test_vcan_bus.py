"""The user-space SocketCAN bus (encoder_conformance.vcan): unmodified can-utils programs, CPython's socket
module and python-can's socketcan interface, all run under the preload library, talk through the hub as
on the kernel's vcan. Every wait is for an event (a line, a frame) with a time-out, never a fixed sleep."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from encoder_conformance.cli import main as cli
from encoder_conformance.vcan import (
    VirtualCan,
    add_interface,
    command,
    hub_pid,
    interfaces,
    up,
)

pytestmark = [
    pytest.mark.skipif(sys.platform != "linux", reason="the virtual CAN bus is Linux only"),
    pytest.mark.skipif(shutil.which("cansend") is None or shutil.which("candump") is None
                       or shutil.which("cangen") is None,
                       reason="can-utils is not installed (cansend, candump, cangen): apt-get install can-utils"),
]

WAIT_S = 5.0


class Program:
    """A program under the preload library whose output lines are collected by a thread."""

    def __init__(self, argv: list[str], env: dict[str, str]) -> None:
        self.argv = argv
        self.process = subprocess.Popen(argv, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True, bufsize=1)
        self.lines: list[str] = []
        self._new = threading.Condition()
        threading.Thread(target=self._collect, daemon=True).start()

    def _collect(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            with self._new:
                self.lines.append(line.rstrip("\n"))
                self._new.notify_all()

    def wait_lines(self, predicate: Callable[[str], bool], count: int = 1, timeout: float = WAIT_S) -> list[str]:
        """The first ``count`` lines passing ``predicate``; AssertionError with the output after ``timeout``."""
        deadline = time.monotonic() + timeout
        with self._new:
            while True:
                found = [line for line in self.lines if predicate(line)]
                if len(found) >= count:
                    return found[:count]
                left = deadline - time.monotonic()
                assert left > 0, f"{self.argv}: {len(found)} of {count} lines in {timeout} s: {self.lines[-20:]}"
                self._new.wait(left)

    def matching(self, predicate: Callable[[str], bool]) -> list[str]:
        with self._new:
            return [line for line in self.lines if predicate(line)]

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(WAIT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


class Bench:
    """A hub with vcan0 (vcan mode) and vcan1 (wire mode) in a short temporary directory."""

    def __init__(self, bus: VirtualCan) -> None:
        self.bus = bus
        self.env = bus.env
        self.programs: list[Program] = []

    def start(self, *argv: str) -> Program:
        program = Program(list(argv), self.env)
        self.programs.append(program)
        return program

    def send(self, interface: str, *frames: str) -> None:
        for frame in frames:
            subprocess.run(["cansend", interface, frame], env=self.env, check=True, timeout=WAIT_S)

    def joined(self, program: Program, interface: str = "vcan0", probe: str = "7FF#") -> None:
        """Send probe frames until ``program`` (a candump that shows them) prints one: it is on the bus."""
        probe_id = probe.split("#")[0]
        deadline = time.monotonic() + WAIT_S
        while not program.matching(lambda line: f" {probe_id}" in line or f"{probe_id}#" in line):
            assert time.monotonic() < deadline, f"{program.argv} did not join; output: {program.lines}"
            self.send(interface, probe)
            with program._new:
                program._new.wait(0.05)

    def close(self) -> None:
        for program in self.programs:
            program.stop()


@pytest.fixture
def bench(preload_library: Path) -> Iterator[Bench]:
    directory = Path(tempfile.mkdtemp(prefix="vcan-"))  # short: AF_UNIX paths are limited to 107 bytes
    try:
        with up(["vcan0"], directory) as bus:
            add_interface(directory, "vcan1", mode="wire")
            bench = Bench(bus)
            try:
                yield bench
            finally:
                bench.close()
    finally:
        shutil.rmtree(directory, ignore_errors=True)


def logged(frame: str) -> Callable[[str], bool]:
    """A ``candump -L`` line of this frame (``vcan0 123#DEADBEEF``)."""
    return lambda line: line.endswith(f" {frame}")


def test_cansend_reaches_candump_with_every_kind_of_frame(bench):
    """Standard and extended ids, data, remote frames (with a DLC), an empty frame and a CAN FD frame."""
    dump = bench.start("candump", "-L", "vcan0")
    bench.joined(dump)
    frames = ["123#DEADBEEF", "12345678#R", "7FF#R3", "1F334455#", "000#0011223344556677"]
    bench.send("vcan0", *frames, "456##1112233445566778899")
    for frame in frames:
        dump.wait_lines(logged(f"vcan0 {frame}"))
    dump.wait_lines(logged("vcan0 456##1112233445566778899000000"))  # FD: 9 bytes padded to DLC 12


def test_candump_filters_are_applied(bench):
    """``vcan0,123:7FF`` passes 123 alone; ``~`` inverts; an SFF-only mask (EFF bit set) drops the 29-bit twin."""
    exact = bench.start("candump", "-L", "vcan0,123:7FF,7FF:7FF")
    inverted = bench.start("candump", "-L", "vcan0,123~7FF")
    sff_only = bench.start("candump", "-L", "vcan0,123:C00007FF,7FF:7FF")
    for program in (exact, inverted, sff_only):
        bench.joined(program)
    bench.send("vcan0", "124#01", "123#02", "00000123#03", "223#04", "123#05")
    assert [line.split()[-1] for line in exact.wait_lines(lambda line: "#0" in line, 3)] == [
        "123#02", "00000123#03", "123#05"]
    assert [line.split()[-1] for line in inverted.wait_lines(lambda line: "#0" in line, 2)] == ["124#01", "223#04"]
    assert [line.split()[-1] for line in sff_only.wait_lines(lambda line: "#0" in line, 2)] == ["123#02", "123#05"]
    bench.send("vcan0", "7FF#FF")  # what comes after the last expected frame shows that nothing else came
    for program in (exact, inverted, sff_only):
        program.wait_lines(lambda line: line.endswith("7FF#FF"))
    assert len(exact.matching(lambda line: "#0" in line)) == 3
    assert len(inverted.matching(lambda line: "#0" in line)) == 2
    assert len(sff_only.matching(lambda line: "#0" in line)) == 2


def test_candump_absolute_timestamps(bench):
    """``candump -t a``: each frame stamped with the wall clock time it was sent, in order."""
    dump = bench.start("candump", "-t", "a", "vcan0")
    bench.joined(dump)
    before = time.time()
    bench.send("vcan0", "321#01", "321#02", "321#03")
    after = time.time()
    lines = dump.wait_lines(lambda line: " 321 " in line, 3)
    stamps = [float(line.split(")")[0].strip(" (")) for line in lines]
    assert stamps == sorted(stamps)
    assert before - 0.05 <= stamps[0], (before, stamps)
    assert stamps[-1] <= after + 0.05, (stamps, after)


def test_five_candumps_each_receive_every_frame(bench):
    dumps = [bench.start("candump", "-L", "-r", "4000000", "vcan0") for _ in range(5)]
    for dump in dumps:
        bench.joined(dump)
    subprocess.run(["cangen", "vcan0", "-g", "0", "-n", "1000", "-I", "2A0", "-L", "4", "-D", "i"],
                   env=bench.env, check=True, timeout=WAIT_S)
    for dump in dumps:
        lines = dump.wait_lines(lambda line: " 2A0#" in line, 1000)
        assert len(set(lines)) == 1000


def test_a_member_killed_mid_run_leaves_the_others_going(bench):
    dumps = [bench.start("candump", "-L", "vcan0") for _ in range(3)]
    for dump in dumps:
        bench.joined(dump)
    sender = bench.start(sys.executable, "-c", textwrap.dedent("""
        import socket, struct, sys
        s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
        s.bind(("vcan0",))
        print("ready", flush=True)
        for line in sys.stdin:
            first, count = (int(part) for part in line.split())
            for i in range(first, first + count):
                s.send(struct.pack("=IB3x8s", 0x300, 2, i.to_bytes(2, "big")))
            print("sent", first + count, flush=True)
        """))
    sender.wait_lines(lambda line: line == "ready")
    assert sender.process.stdin is not None
    sender.process.stdin.write("0 100\n")
    sender.process.stdin.flush()
    dumps[1].wait_lines(lambda line: " 300#0063" in line)  # the victim is receiving
    dumps[1].process.send_signal(signal.SIGKILL)
    dumps[1].process.wait(WAIT_S)
    sender.process.stdin.write("100 100\n")
    sender.process.stdin.flush()
    sender.wait_lines(lambda line: line == "sent 200")
    for survivor in (dumps[0], dumps[2]):
        assert len(survivor.wait_lines(lambda line: " 300#" in line, 200)) == 200
    newcomer = bench.start("candump", "-L", "vcan0")
    bench.joined(newcomer)
    sender.process.stdin.close()
    assert sender.process.wait(WAIT_S) == 0


def test_a_stopped_member_loses_frames_and_is_told_the_others_do_not(bench):
    """A reader that stops reading fills its queue (about as many frames as its receive buffer would hold
    in the kernel) and loses the rest, counted by SO_RXQ_OVFL (``candump -d``); the sender and the
    other readers are not held up."""
    stopped = bench.start("candump", "-L", "-d", "vcan0")
    live = bench.start("candump", "-L", "-r", "4000000", "vcan0")
    for dump in (stopped, live):
        bench.joined(dump)
    stopped.process.send_signal(signal.SIGSTOP)
    try:
        subprocess.run(["cangen", "vcan0", "-g", "0", "-n", "3000", "-I", "100", "-L", "1", "-D", "i"],
                       env=bench.env, check=True, timeout=WAIT_S)
        live.wait_lines(lambda line: " 100#" in line, 3000)
    finally:
        stopped.process.send_signal(signal.SIGCONT)
    bench.send("vcan0", "7FF#01")
    stopped.wait_lines(logged("7FF#01"))
    report = stopped.wait_lines(lambda line: line.startswith("DROPCOUNT"))[0]
    dropped = int(report.split("dropped ")[1].split()[0])
    kept = len(stopped.matching(lambda line: " 100#" in line))
    assert kept + dropped == 3000
    assert 200 < kept < 1000, kept  # the kernel's default receive buffer holds 477 such frames


PYTHON_CAN_SCRIPT = """
import json, sys, can
def out(**kw): print(json.dumps(kw), flush=True)
def seen(m): return {"id": m.arbitration_id, "ext": m.is_extended_id, "rtr": m.is_remote_frame, "data": m.data.hex(),
                     "is_rx": m.is_rx, "ts": m.timestamp, "channel": m.channel}
bus = can.Bus(interface="socketcan", channel=sys.argv[1], receive_own_messages=True,
              can_filters=[{"can_id": 0x580, "can_mask": 0x780}])
import subprocess  # a vfork() child closes the inherited fds in the parent's memory: the bus must stay ours
subprocess.run(["true"], check=True)
out(event="ready")
got = [bus.recv(5) for _ in range(2)]
out(event="received", frames=[seen(m) for m in got if m is not None])
bus.set_filters(None)
bus.send(can.Message(arbitration_id=0x604, data=bytes.fromhex("4000100000000000"), is_extended_id=False))
own = bus.recv(5)
out(event="own", frame=seen(own) if own else None)
bus.shutdown()
"""


@pytest.mark.parametrize(("interface", "others_rx"), [("vcan0", False), ("vcan1", True)])
def test_python_can_socketcan_under_the_preload(bench, tmp_path, interface, others_rx):
    """python-can's socketcan bus (recvmsg with SO_TIMESTAMPNS, filters, receive_own_messages) with can-utils,
    also after the process started a program (CPython's subprocess: vfork, the child closing every fd).
    vcan0 (vcan mode) flags every frame as sent on this host, so python-can says is_rx=False as on the
    kernel's vcan; vcan1 (wire mode) flags only the bus's own frames, as a real adapter does."""
    dump = bench.start("candump", "-L", interface)
    bench.joined(dump, interface)
    script = tmp_path / "python_can_peer.py"
    script.write_text(PYTHON_CAN_SCRIPT, encoding="utf-8")
    peer = bench.start(sys.executable, str(script), interface)
    peer.wait_lines(lambda line: '"ready"' in line)
    sent_at = time.time()
    bench.send(interface, "123#01", "584#4300100091010F00", "1F000584#AA")  # 123 is filtered out
    received = json.loads(peer.wait_lines(lambda line: '"received"' in line)[0])["frames"]
    assert [(f["id"], f["ext"], f["data"]) for f in received] == [(0x584, False, "4300100091010f00"),
                                                                  (0x1F000584, True, "aa")]
    assert all(f["is_rx"] is others_rx and f["channel"] == interface for f in received)
    assert all(abs(f["ts"] - sent_at) < 2.0 for f in received)
    own = json.loads(peer.wait_lines(lambda line: '"own"' in line)[0])["frame"]
    assert own is not None
    assert (own["id"], own["is_rx"]) == (0x604, False)
    dump.wait_lines(logged(f"{interface} 604#4000100000000000"))
    assert peer.process.wait(WAIT_S) == 0


RAW_SOCKET_SCRIPT = r'''
import errno, fcntl, json, select, socket, struct, time
CAN = struct.Struct("=IB3x8s")
FD = struct.Struct("=IBB2x64s")
SO_TIMESTAMPNS, SIOCGSTAMP = 35, 0x8906
checks = {}
def raw(interface=None, **options):
    s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    for name, value in options.items():
        s.setsockopt(socket.SOL_CAN_RAW, getattr(socket, name), value)
    if interface is not None:
        s.bind((interface,))
    return s
def frame(can_id, data=b""):
    return CAN.pack(can_id, len(data), data)
def next_id(s, timeout=5.0):
    assert select.select([s], [], [], timeout)[0], "no frame"
    return CAN.unpack(s.recv(72)[:16])[0]
def error_name(call):
    try:
        call()
    except OSError as error:
        return errno.errorcode[error.errno]
    return "no error"

checks["unknown interface"] = error_name(lambda: raw("nosuch0"))
a = raw("vcan0")
b = raw()
b.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
b.bind(("vcan0",))
checks["getsockname"] = b.getsockname()
checks["domain type protocol"] = [b.getsockopt(socket.SOL_SOCKET, o) for o in
                                  (socket.SO_DOMAIN, socket.SO_TYPE, socket.SO_PROTOCOL)]
pair = struct.pack("=IIII", 0x100, 0x700, 0x7FF, 0x7FF)
b.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_FILTER, pair)
checks["filters read back"] = b.getsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_FILTER, 16) == pair
sent = time.time()
a.send(frame(0x123, b"\x01\x02"))
data, ancillary, flags, address = b.recvmsg(16, 64)
level, kind, stamp = ancillary[0]
seconds, nanoseconds = struct.unpack("=qq", stamp)
checks["recvmsg"] = {"id": CAN.unpack(data)[0], "address": address, "cmsg": [level, kind],
                     "stamp ok": abs(seconds + nanoseconds / 1e9 - sent) < 2,
                     "dontroute": bool(flags & socket.MSG_DONTROUTE), "confirm": bool(flags & 0x800)}
seconds, microseconds = struct.unpack("=qq", fcntl.ioctl(b, SIOCGSTAMP, bytes(16)))
checks["SIOCGSTAMP"] = abs(seconds + microseconds / 1e6 - sent) < 2
own = raw("vcan0", CAN_RAW_RECV_OWN_MSGS=1)
own.send(frame(0x7FF, b"\x0a"))
data, _, flags, _ = own.recvmsg(16)
checks["own flags"] = [CAN.unpack(data)[0], bool(flags & socket.MSG_DONTROUTE), bool(flags & 0x800)]
checks["FD without CAN_RAW_FD_FRAMES"] = error_name(lambda: a.send(FD.pack(0x123, 12, 0, bytes(64))))
fd_sender = raw("vcan0", CAN_RAW_FD_FRAMES=1)
fd_reader = raw("vcan0", CAN_RAW_FD_FRAMES=1)
classic = raw("vcan0")
fd_sender.send(FD.pack(0x111, 12, 1, bytes(range(64))))
fd_sender.send(frame(0x112))
checks["FD frame"] = [len(fd_reader.recv(72)), next_id(fd_reader), next_id(classic)]
quiet = raw("vcan0", CAN_RAW_LOOPBACK=0)
quiet.send(frame(0x113))
a.send(frame(0x114))
checks["loopback off: unheard"] = next_id(classic)
other = raw("vcan1")
anywhere = raw("")
a.sendto(frame(0x115), ("vcan1",))
checks["sendto vcan1"] = [next_id(other), anywhere.recvfrom(16)[1]]
a.send(frame(0x116))
checks["any"] = anywhere.recvfrom(16)[1]
errors = raw("vcan0")
errors.setsockopt(socket.SOL_CAN_RAW, 2, 0x4)  # CAN_RAW_ERR_FILTER (CPython has no name for it)
a.send(frame(0x20000002 | 0x1, bytes(8)))  # an error frame of class 0x2 (lost arbitration): masked out
a.send(frame(0x20000004, bytes(8)))  # controller problems: passes the mask
a.send(frame(0x117))
checks["error mask"] = [hex(next_id(errors)), hex(next_id(errors))]
checks["XL refused"] = error_name(lambda: a.setsockopt(socket.SOL_CAN_RAW, 7, 1))
checks["send unbound"] = error_name(lambda: raw().send(frame(0x118)))
print(json.dumps(checks))
'''


def test_cpython_socket_module_sees_kernel_semantics(bench, tmp_path):
    """CPython's socket module under the preload: addresses, options, stamps, flags, FD, loopback, sendto,
    bind to any, error masks as the kernel's CAN_RAW has them."""
    script = tmp_path / "raw_socket_checks.py"
    script.write_text(RAW_SOCKET_SCRIPT, encoding="utf-8")
    done = subprocess.run([sys.executable, str(script)], env=bench.env, capture_output=True, text=True,
                          timeout=20)
    assert done.returncode == 0, done.stdout + done.stderr
    checks = json.loads(done.stdout)
    assert checks == {
        "unknown interface": "ENODEV",
        "getsockname": ["vcan0"],
        "domain type protocol": [29, 3, 1],
        "filters read back": True,
        "recvmsg": {"id": 0x123, "address": ["vcan0"], "cmsg": [1, 35], "stamp ok": True, "dontroute": True,
                    "confirm": False},
        "SIOCGSTAMP": True,
        "own flags": [0x7FF, True, True],
        "FD without CAN_RAW_FD_FRAMES": "EINVAL",
        "FD frame": [72, 0x112, 0x112],
        "loopback off: unheard": 0x114,
        "sendto vcan1": [0x115, ["vcan1"]],
        "any": ["vcan0"],
        "error mask": ["0x20000004", "0x117"],
        "XL refused": "ENOPROTOOPT",
        "send unbound": "ENXIO",
    }


EPOLL_SCRIPT = """
import errno, json, select, socket, time
s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
s.bind(("vcan0",))
poller = select.epoll()
poller.register(s, select.EPOLLIN)
print("ready", flush=True)
events, errors, until = 0, [], None
while (until is None or time.monotonic() < until) and events < 1000:
    for _ in poller.poll(0.05):
        events += 1
        try:
            s.recv(16)
        except OSError as error:
            errors.append(errno.errorcode[error.errno])
            until = until or time.monotonic() + 0.5  # watch a while longer: nothing more must come
print(json.dumps({"events": events, "errors": errors}), flush=True)
"""


def test_the_interface_is_down_without_its_hub(bench):
    """The hub stopping takes the interfaces down: a bound reader is told once (ENETDOWN) and then its
    socket stays quiet (an epoll loop does not spin, as CANopenLinux's would), bind fails with ENETDOWN."""
    dump = bench.start("candump", "-L", "vcan0")
    bench.joined(dump)
    loop = bench.start(sys.executable, "-c", EPOLL_SCRIPT)
    loop.wait_lines(lambda line: line == "ready")
    bench.bus.stop()
    dump.wait_lines(lambda line: "Network is down" in line)
    assert json.loads(loop.wait_lines(lambda line: line.startswith("{"))[0]) == {"events": 1, "errors": ["ENETDOWN"]}
    failed = subprocess.run(["cansend", "vcan0", "123#00"], env=bench.env, capture_output=True, text=True,
                            timeout=WAIT_S)
    assert failed.returncode != 0
    assert "Network is down" in failed.stdout + failed.stderr


def test_command_up_status_down(preload_library, capsys):
    directory = Path(tempfile.mkdtemp(prefix="vcan-"))
    try:
        assert command.main(["up", "-d", str(directory), "--mtu", "16", "can7"]) == 0
        exports = capsys.readouterr().out
        assert f"export LD_PRELOAD={preload_library}" in exports
        assert f"export ENCODER_CONFORMANCE_VCAN_DIR={directory.resolve()}" in exports
        assert hub_pid(directory) is not None
        assert {i.name: (i.mtu, i.mode) for i in interfaces(directory).values()} == {"can7": (16, "vcan")}
        assert command.main(["-d", str(directory), "status"]) == 0
        assert "can7: ifindex 1000, mtu 16" in capsys.readouterr().out
        assert cli.main(["vcan", "-d", str(directory), "status"]) == 0  # the same through the tool's command
        assert "can7: ifindex 1000, mtu 16" in capsys.readouterr().out
        assert command.main(["down", "-d", str(directory)]) == 0
        assert hub_pid(directory) is None
        assert interfaces(directory) == {}
        assert command.main(["up", "-d", str(directory), "bad/name"]) == 4
        assert command.main(["frobnicate"]) == 4
    finally:
        command.main(["down", "-d", str(directory)])
        shutil.rmtree(directory, ignore_errors=True)


LATENCY_SCRIPT = """
import socket, struct, sys, time
s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
s.bind(("vcan0",))
F = struct.Struct("=IB3x8s")
mine, theirs = (0x100, 0x101) if sys.argv[1] == "ping" else (0x101, 0x100)
s.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_FILTER, struct.pack("=II", theirs, 0x7FF))
print("ready", flush=True)
if sys.argv[1] == "echo":
    while s.recv(16)[8] != 0xFF:
        s.send(F.pack(mine, 8, bytes(8)))
else:
    input()
    rtts = []
    for _ in range(int(sys.argv[2])):
        start = time.perf_counter()
        s.send(F.pack(mine, 8, bytes(8)))
        s.recv(16)
        rtts.append(time.perf_counter() - start)
    s.send(F.pack(mine, 8, b"\\xff" + bytes(7)))
    rtts.sort()
    print(f"{rtts[len(rtts) // 2] * 1e6:.0f} {rtts[int(len(rtts) * 0.99)] * 1e6:.0f}", flush=True)
"""


def test_throughput_and_latency(bench, tmp_path, capsys):
    """10,000 frames from cangen to candump, none lost; round trips between two Python programs."""
    count = 10_000
    dump = bench.start("candump", "-L", "-r", "8000000", "vcan0")
    bench.joined(dump)
    start = time.perf_counter()
    subprocess.run(["cangen", "vcan0", "-g", "0", "-n", str(count), "-I", "5A5", "-L", "8", "-D", "i"],
                   env=bench.env, check=True, timeout=30)
    sent = time.perf_counter() - start
    dump.wait_lines(lambda line: " 5A5#" in line, count, timeout=30)
    received = time.perf_counter() - start
    script = tmp_path / "latency.py"
    script.write_text(LATENCY_SCRIPT, encoding="utf-8")
    echo = bench.start(sys.executable, str(script), "echo")
    ping = bench.start(sys.executable, str(script), "ping", "1000")
    echo.wait_lines(lambda line: line == "ready")
    ping.wait_lines(lambda line: line == "ready")
    assert ping.process.stdin is not None
    ping.process.stdin.write("go\n")
    ping.process.stdin.flush()
    median_us, p99_us = (int(x) for x in ping.wait_lines(lambda line: line[:1].isdigit(), timeout=30)[0].split())
    with capsys.disabled():
        print(f"\nvcan: {count} frames cangen -> candump in {received:.2f} s ({count / received:,.0f} frames/s; "
              f"cangen done after {sent:.2f} s); round trip Python <-> Python: median {median_us} us, "
              f"p99 {p99_us} us")
    assert median_us < 20_000

