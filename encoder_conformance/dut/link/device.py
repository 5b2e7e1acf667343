"""The link to the device under test: SDO, raw frames and the waits each owes, the one object every protocol of
``dut/`` talks through (``dut/device.py``'s ``DeviceUnderTest`` adds a face per protocol on top of it).

Whether a simulator or a real encoder is on the bus is invisible here. Once the device stops answering (or the bus
is gone), ``lost`` is set and every later call fails at once with the first reason (labgrid's "broken strategy"
pattern). Once the run is stopping (Ctrl-C), calls raise RunInterrupted except inside ``in_custody()``, the restore's
own access.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Literal

import can
import canopen
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

import encoder_conformance.dut.sdo.sdo_frames as sdo_frames
from encoder_conformance.cia.cia301 import (
    HEARTBEAT_BASE,
    NODE_TRANSMIT_BASES,
    SDO_REQUEST_BASE,
    SDO_RESPONSE_BASE,
    SYNC_COB_ID,
    TPDO_BASES,
)
from encoder_conformance.dut.link.frames import FrameLog, Mark, format_frames
from encoder_conformance.dut.link.late_frames import restarts, writes
from encoder_conformance.dut.link.time_budget import BUDGET
from encoder_conformance.dut.link.windows import Windows
from encoder_conformance.errors import BusLostError, DutLostError, EncoderConformanceError, RunInterrupted
from encoder_conformance.models.encoder.freeze import FreezeRule
from encoder_conformance.profile.quirk_effects import SilentUntilBusTraffic
from encoder_conformance.profile.schema import DeviceProfile

#: an answer the device owes is waited for 4 x what it owes, and at least this long: a late answer is a loaded
#: tester host far more often than a slow device (SDO and LSS answers alike)
ANSWER_FLOOR_S = 0.3


def answer_window(device_s: float) -> float:
    """How long to wait for an answer the device owes within ``device_s`` (a silence: ``silence_window``)."""
    return max(ANSWER_FLOOR_S, 4 * device_s)

#: exact: the code CiA 301 (or the manual, through a quirk) names for the situation; family: any code of
#: its family (the same code but for the last digit, e.g. 06090031h for 06090030h), as the CiA
#: conformance test tool accepts
AbortCodeMode = Literal["exact", "family"]
STALE_REQUESTS = 8  # an SDO reply that fits one of this many requests before the current one is a late answer

__all__ = ["DeviceLink", "HeartbeatSample", "SdoAborted", "wake_if_silent"]
#: failed probes in a row before the device counts as gone (one late answer on a busy PC is not a dead device)
LOST_AFTER_PROBES = 2
#: the tester's frames a lost device's verdict names (the last sent before it stopped answering)
LAST_SENT = 6


class SdoAborted(SdoAbortedError, EncoderConformanceError):
    """canopen's SdoAbortedError as the dut layer raises it (``except SdoAbortedError`` still catches it), and a
    member of the library's exception tree (``errors.py`` draws it; defined here, as errors.py imports no canopen).

    canopen's own ``__eq__`` reads ``other.code`` of whatever it is compared with: hypothesis, comparing the
    failures it found with the exceptions in their context, crashed with AttributeError (issue 26). This one is
    equal only to an abort with the same code, and is raised outside canopen's except block, so that canopen's
    exception never travels in the context of a test's failure.
    """

    def __eq__(self, other: object) -> bool:
        return isinstance(other, SdoAbortedError) and self.code == other.code

    def __hash__(self) -> int:
        return hash(self.code)


@dataclass(frozen=True)
class HeartbeatSample:
    timestamp: float
    state: int
    dlc: int


class DeviceLink:
    """A CANopen node on a bus, with waits that take their limits from the profile."""

    def __init__(self, network: canopen.Network, frames: FrameLog, profile: DeviceProfile, node_id: int) -> None:
        self.network = network
        self.frames = frames
        self.profile = profile
        self.node_id = node_id
        self.node = canopen.RemoteNode(node_id, canopen.ObjectDictionary())
        network.add_node(self.node)
        self.node.sdo.RESPONSE_TIMEOUT = answer_window(profile.timing.sdo_response_max_ms / 1000)
        self.windows = Windows(profile.timing)  # silence windows; measured at the start of a run (answer_times.py)
        self._lost: str | None = None
        self.bench_failure: str | None = None  # the bench failed (power switch): nothing about the device shown
        self.lost_frames = ""  # the last frames the tester sent before the device stopped answering
        self.stopping: str | None = None  # why the run is ending early (Ctrl-C, SIGTERM)
        self.tester_notes: list[str] = []  # what the tester saw that is not a verdict (drained into evidence)
        self.abort_codes: AbortCodeMode = "exact"  # how SDO abort codes are judged (--abort-codes)
        self._custody = threading.local()
        self._freeze = FreezeRule.of(profile)
        self._executing_until = 0.0  # the device executes a write until then (its position is frozen)

    # -- liveness ------------------------------------------------------------------------
    @property
    def lost(self) -> str | None:
        """Why the device can no longer be tested (bus gone, bench failed, device silent), or None."""
        return self.frames.closed_reason or self.bench_failure or self._lost

    @property
    def device_lost(self) -> bool:
        """The device itself stopped answering (a finding about it), not the bus or the bench."""
        return self._lost is not None and not self.frames.closed_reason and not self.bench_failure

    @property
    def bus_lost(self) -> bool:
        return self.frames.closed_reason is not None

    @property
    def usable(self) -> bool:
        """True while tests (and their clean-up) may talk to the device."""
        return not self.lost and not self.stopping

    def _check_alive(self) -> None:
        if self.frames.closed_reason:
            raise BusLostError(self.frames.closed_reason)
        in_custody = getattr(self._custody, "active", False)
        if self.bench_failure or (self._lost and not in_custody):  # the restore may still try to reach it
            raise DutLostError(f"device stopped answering earlier: {self.lost}")
        if self.stopping and not in_custody:
            raise RunInterrupted(self.stopping)

    def mark_lost(self, reason: str, sent: list[can.Message] | None = None) -> None:
        """The device stopped answering: later calls fail at once; the frames sent last (``sent``, default the
        log's) are kept for the verdict."""
        if self._lost is None:
            self.lost_frames = format_frames((self._sent_last() if sent is None else sent)[-LAST_SENT:]) or "  (none)"
        self._lost = self._lost or reason

    def _sent_last(self) -> list[can.Message]:
        return [m for m in self.frames.last(60) if not m.is_rx]

    def mark_bench_failed(self, reason: str) -> None:
        """The bench (power switch, drive) failed: the run cannot go on, and nothing about the device was shown."""
        self.bench_failure = self.bench_failure or reason

    def stop(self, reason: str) -> None:
        """The run is ending early: from now on only ``in_custody()`` may talk to the device."""
        self.stopping = self.stopping or reason

    @contextmanager
    def in_custody(self) -> Iterator[DeviceLink]:
        """Device access for the snapshot and the restore, also while the run is stopping."""
        self._custody.active = True
        try:
            yield self
        finally:
            self._custody.active = False

    @property
    def sdo_timeout(self) -> float:
        return self.node.sdo.RESPONSE_TIMEOUT

    def silence_window(self, figure: str) -> float:
        """How long to watch for a frame the device must NOT send, of the kind the profile's timing ``figure``
        bounds (``dut/link/windows.py``: from the device's measured answers, the host's lateness, the manual)."""
        return self.windows.silence_s(figure)

    @property
    def sdo_silence_s(self) -> float:
        """Watch this long for an SDO answer that must not come."""
        return self.silence_window("sdo_response_max_ms")

    @property
    def pdo_silence_s(self) -> float:
        """Watch this long after a SYNC (or RTR) for a TPDO that must not come."""
        return self.silence_window("pdo_response_max_ms")

    @property
    def pdo_answer_s(self) -> float:
        """Wait up to this long for a frame the device owes within ``pdo_response_max_ms`` of its trigger (a TPDO
        after a SYNC or an RTR, its first SYNC as producer): ``answer_window``, the wait ends when it comes."""
        return answer_window(self.profile.timing.pdo_response_max_ms / 1000)

    # -- SDO through canopen (normal access) ------------------------------------------------
    def read(self, index: int, sub: int = 0) -> bytes:
        """Upload through canopen's client (expedited or segmented). Aborts raise SdoAbortedError."""
        self._check_alive()
        mark = self.frames.mark()
        try:
            with BUDGET.booking("sdo"):
                return self.node.sdo.upload(index, sub)
        except SdoCommunicationError as exc:
            raise self._timeout(f"SDO upload {index:04X}h.{sub:02X}", exc, mark) from None
        except SdoAbortedError as exc:
            code = exc.code
        raise SdoAborted(code)  # outside canopen's except block: see SdoAborted

    def write(self, index: int, sub: int, data: bytes) -> None:
        self._check_alive()
        mark = self.frames.mark()
        try:
            with BUDGET.booking("sdo"):
                self.node.sdo.download(index, sub, data)
            if self._freeze is not None:
                until = time.monotonic() + self._freeze.duration_s(index, int.from_bytes(data, "little"))
                self._executing_until = max(self._executing_until, until)
            return
        except SdoCommunicationError as exc:
            raise self._timeout(f"SDO download {index:04X}h.{sub:02X}", exc, mark) from None
        except SdoAbortedError as exc:
            code = exc.code
        raise SdoAborted(code)  # outside canopen's except block: see SdoAborted

    def wait_until_executed(self) -> None:
        """Wait out the execution time the manual gives for the writes made so far (quirk
        ``position_frozen_during_execution``): the device, not one test's helper, keeps it, so a test does not
        inherit a position frozen by the put-back of the test before."""
        remaining = self._executing_until - time.monotonic()
        if remaining > 0:
            with BUDGET.booking("execution"):
                time.sleep(remaining)  # nothing on the bus shows the end of the execution

    def read_uint(self, index: int, sub: int = 0) -> int:
        return int.from_bytes(self.read(index, sub), "little")

    def write_uint(self, index: int, sub: int, value: int, size: int) -> None:
        self.write(index, sub, value.to_bytes(size, "little"))

    def _timeout(self, what: str, exc: Exception, since: Mark) -> AssertionError:
        """A request went unanswered: the device is gone only if it stays silent on every channel
        (a stopped device answers no SDO but still sends its heartbeat)."""
        sent = self._sent_last()  # before the probes: what the device went silent after
        if not any(self.responds() for _ in range(LOST_AFTER_PROBES)) and not self.heard_since(since):
            self.mark_lost(f"no answer to {what} nor to {LOST_AFTER_PROBES} probes of 1000h, and no frame from it",
                           sent)
        return AssertionError(f"{what}: {exc}\nlast frames:\n{format_frames(self.frames.last(12))}")

    def heard_since(self, mark: Mark) -> bool:
        """Did the node send any frame (heartbeat, PDO, EMCY, SDO) after ``mark``?"""
        own = self._own_cob_ids()
        return bool(self.frames.since(mark, lambda m: m.is_rx and m.arbitration_id in own))

    def responds(self, timeout: float | None = None) -> bool:
        """One raw read of 1000h: does the node answer SDO at all (within ``timeout``, default the SDO timeout)?"""
        return self.sdo_request(sdo_frames.upload_request(0x1000, 0), check_alive=False, timeout=timeout) is not None

    # -- raw SDO (byte-exact) ------------------------------------------------------------
    def sdo_request_unanswered(self, request: bytes, provoked_by: str,
                               basis: str) -> sdo_frames.SdoResponse | None:
        """Send ``request``, which ``basis`` says the device must not answer, and watch its silence window; the
        reply, or None. The window is declared to the late-frame ledger, so an answer after it is still charged to
        this request (``late_frames.py``)."""
        reply = self.sdo_request(request, timeout=self.sdo_silence_s)
        self.frames.late.close_sdo(self.node_id, request, provoked_by, basis)
        return reply

    def forbid_until_written(self, matches: Callable[[can.Message], bool], what: str, provoked_by: str, basis: str,
                             entry: tuple[int, int], value: bytes) -> None:
        """From now ``matches`` must not come until ``entry`` (index, sub) is written other than ``value`` (as it is
        now) or the node restarts: one after the test's own window is still charged to it (``late_frames.py``)."""
        written = writes(self.node_id, *entry, unless=value)
        restarted = restarts(self.node_id)
        self.frames.late.forbid(matches, what, provoked_by, basis, lambda m: written(m) or restarted(m))

    def sdo_request(self, request: bytes, check_alive: bool = True,
                    timeout: float | None = None) -> sdo_frames.SdoResponse | None:
        """Send one raw SDO request frame; the response frame, or None if none came within ``timeout``
        (default the SDO timeout; pass ``sdo_silence_s`` where no answer is expected).

        The answer is matched by content (``sdo_frames.answers``: command specifier and multiplexer), not
        by order: a reply that fits one of the last requests before this one is a late answer to it,
        noted in ``tester_notes`` and skipped. A reply that fits no request is the device's answer (a
        wrong multiplexer is the caller's to judge, not mistaken for silence).
        """
        if check_alive:
            self._check_alive()
        mark = self.frames.mark()
        self.network.send_message(SDO_REQUEST_BASE + self.node_id, request)
        wait = self.sdo_timeout if timeout is None else timeout
        earlier: list[bytes] = []  # the requests before this one, read from the log only for a reply that does not fit

        def is_answer(msg: can.Message) -> bool:
            if not self._is_sdo_response(msg):
                return False
            data = bytes(msg.data)
            if sdo_frames.answers(request, data):
                return True
            if not earlier:
                earlier[:] = [bytes(m.data) for m in self.frames.before(mark, self._is_sdo_request)][-STALE_REQUESTS:]
            # a reply that fits no earlier request is the device's own, wrong answer to this one
            return not any(sdo_frames.answers(e, data) for e in earlier)

        reply = self.frames.wait_for(is_answer, wait, after=mark)
        if reply is None:
            return None
        stale = [m for m in self.frames.since(mark, self._is_sdo_response) if m is not reply
                 and m.timestamp <= reply.timestamp]
        if stale:
            self.tester_notes.append(
                f"request {request.hex(' ').upper()}: skipped {len(stale)} SDO response(s) that do not answer it "
                f"(late answers to an earlier request?): " + ", ".join(bytes(m.data).hex(" ").upper() for m in stale)
            )
        return sdo_frames.SdoResponse(bytes(reply.data))

    def _is_sdo_request(self, msg: can.Message) -> bool:
        return not msg.is_rx and msg.arbitration_id == SDO_REQUEST_BASE + self.node_id

    def _is_sdo_response(self, msg: can.Message) -> bool:
        return msg.is_rx and msg.arbitration_id == SDO_RESPONSE_BASE + self.node_id and not msg.is_remote_frame

    def expect_abort(self, request: bytes) -> sdo_frames.SdoResponse:
        """Send a request that must be refused; returns the abort response (asserts one came)."""
        response = self.sdo_request(request)
        if response is None:
            raise AssertionError(
                f"no SDO response to {request.hex(' ').upper()} within {self.sdo_timeout * 1000:.0f} ms\n"
                f"last frames:\n{format_frames(self.frames.last(8))}"
            )
        return response

    def send_sync(self) -> Mark:
        """One SYNC on the pre-defined COB-ID 080h; a mark before it."""
        return self.send(SYNC_COB_ID)

    def send_sdo(self, request: bytes) -> Mark:
        """One raw SDO request frame, not waiting for an answer (the caller inspects the log); a mark before it."""
        return self.send(SDO_REQUEST_BASE + self.node_id, request)

    def send(self, cob_id: int, data: bytes = b"", remote: bool = False) -> Mark:
        """Send one raw frame (SYNC, a request the DUT layer has no helper for); a mark before it."""
        self._check_alive()
        mark = self.frames.mark()
        self.network.send_message(cob_id, data, remote=remote)
        return mark

    # -- NMT error control (the commands: dut/nmt/commands.py) ------------------------------
    def is_heartbeat(self, msg: can.Message) -> bool:
        return msg.is_rx and msg.arbitration_id == HEARTBEAT_BASE + self.node_id and not msg.is_remote_frame

    def wait_bootup(self, after: Mark, timeout: float | None = None) -> can.Message | None:
        limit = timeout if timeout is not None else self.profile.timing.bootup_max_ms / 1000
        with BUDGET.booking("boot-up"):
            return self.frames.wait_for(lambda m: self.is_heartbeat(m) and bytes(m.data) == b"\x00", limit, after)

    def wait_heartbeat(self, after: Mark, timeout: float, state: int | None = None) -> can.Message | None:
        """Next heartbeat (not boot-up) after ``after``; with ``state``, the next one reporting it."""

        def match(msg: can.Message) -> bool:
            if not self.is_heartbeat(msg) or not msg.data or msg.data[0] == 0:
                return False
            return state is None or msg.data[0] == state

        return self.frames.wait_for(match, timeout, after)

    def heartbeats(self, after: Mark, count: int, timeout: float) -> list[HeartbeatSample]:
        hits = self.frames.wait_count(lambda m: self.is_heartbeat(m) and bool(m.data), count, timeout, after)
        return [HeartbeatSample(m.timestamp, m.data[0], m.dlc) for m in hits]

    def pdos_counted(self, predicate: Callable[[can.Message], bool], expected: int, after: Mark,
                     timeout: float) -> list[can.Message]:
        """The TPDOs ``predicate`` matches after ``after``, at most one more than ``expected``: waits up to
        ``timeout`` for ``expected`` of them, then one PDO silence window in which a surplus one would come (a frame
        that must not come: the silence window, not a settle time)."""
        self.frames.wait_count(predicate, expected, timeout, after)
        self.frames.quiet_period(predicate, self.pdo_silence_s)
        return self.frames.since(after, predicate)[: expected + 1]

    def frames_from_node(self, after: Mark, duration: float) -> list[can.Message]:
        """Every frame the node sends in an observation window of ``duration`` seconds."""
        own = self._own_cob_ids()
        return self.frames.quiet_period(lambda m: m.is_rx and m.arbitration_id in own, duration, after)

    def _own_cob_ids(self) -> set[int]:
        return {b + self.node_id for b in NODE_TRANSMIT_BASES}

    def is_pdo(self, msg: can.Message) -> bool:
        return msg.is_rx and msg.arbitration_id in {b + self.node_id for b in TPDO_BASES}


def wake_if_silent(dut: DeviceLink) -> str | None:
    """Devices with automatic bit-rate detection stay silent after power-on until they see a
    frame; send one SYNC as the manual prescribes. Returns the quirk id relied on, if any."""
    found = dut.profile.quirk(SilentUntilBusTraffic)
    if found is None:
        return None
    dut.send(SYNC_COB_ID, b"")
    return found.id
