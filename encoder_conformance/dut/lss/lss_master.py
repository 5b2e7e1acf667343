"""An LSS master (CiA 305) on raw frames: every service, and a fastscan that waits only for what a slave owes.

Why not canopen's LssMaster: it sleeps 0.5 s per '1' bit of a fastscan and 0.2 s per selective frame
(16.9 s to find one slave), reads no identify answers and only finds non-configured slaves
(../shared/reference/python-stack-measured.md §2.5). Here each step waits for the answer on the frame log
and returns as soon as it is there; only a step nobody answers costs the full response window.

A request never follows a slave's answer closer than one frame time (``LssMaster.frame_s``): on a wire the
answer and the request each take that long, but a simulated bus (the user-space SocketCAN bus, a virtual
channel) delivers both at once, and a slave that is still finishing its answer drops the request (CANopenNode
clears its "response pending" flag just after sending: a request 92 µs after its answer was lost). Only the
rest of that time is waited, counted from the answer's timestamp, so a step whose answer is older costs nothing.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import can

from encoder_conformance.cia.cia305 import (
    ADDRESS_PARTS,
    FASTSCAN_RESET_BIT,
    IDENTIFY_RANGE_COMMANDS,
    INQUIRE_COMMANDS,
    MASTER_COB_ID,
    SELECTIVE_COMMANDS,
    SLAVE_COB_ID,
    LssCommand,
    LssState,
    answer_command,
)
from encoder_conformance.dut.link.device import answer_window
from encoder_conformance.dut.link.frames import FrameLog, Mark
from encoder_conformance.dut.link.time_budget import BUDGET
from encoder_conformance.dut.link.windows import UNMEASURED_MARGIN_S, Windows

#: the profile's timing figure of an LSS answer (its silence window's name)
LSS_FIGURE = "lss_response_ms"
#: the shortest response window a learned one may be (``LssMaster.learned_window``)
WINDOW_FLOOR_S = 0.01
#: after an answer, how long other slaves' copies of it may still arrive (on a real bus identical
#: answers merge into one frame; a simulated bus delivers each)
ECHO_S = 0.003
#: bits of a CAN frame with 8 data bytes and an 11-bit identifier: 111 without stuff bits (the 3-bit
#: intermission included), up to 135 with them; 125 makes it 1 ms at 125 kbit/s
FRAME_BITS = 125
#: the shortest time between a slave's answer and the next request when the bit rate is not known:
#: one frame time at 125 kbit/s (8 data bytes: 1 ms)
FRAME_S = FRAME_BITS / 125_000
#: a frame timestamp at most this old is on the host's wall clock (time.time(): socketcan, virtual, the
#: user-space bus); any other is on an adapter's own clock, and the frame counts as just arrived
HOST_STAMP_AGE_S = 60.0


@dataclass(frozen=True)
class LssAddress:
    """The LSS address: 1018h sub 1..4."""

    vendor: int
    product: int
    revision: int
    serial: int

    def parts(self) -> tuple[int, int, int, int]:
        return self.vendor, self.product, self.revision, self.serial

    def describe(self) -> str:
        return ", ".join(f"{name} 0x{value:08X}" for name, value in zip(ADDRESS_PARTS, self.parts(), strict=True))


@dataclass(frozen=True)
class LssAnswer:
    """A configure / store answer: error code (0 = success) and the manufacturer's code for error FFh."""

    error: int
    specific: int = 0


Send = Callable[[int, bytes], None]


class LssMaster:
    """LSS services over ``send`` (one frame on 7E5h) and the frame log (answers on 7E4h)."""

    def __init__(self, send: Send, frames: FrameLog, response_s: float, bitrate: int | None = None,
                 windows: Windows | None = None) -> None:
        """``bitrate``: the bus's bit rate, bit/s, if known: a request keeps one frame time at it after an answer
        (``frame_s``); else one frame time at 125 kbit/s (``FRAME_S``). ``windows``: the device's silence windows
        (``DeviceLink.windows``): an answer that must not come is watched for its LSS window, and every answer's
        time is observed there; without it the profile's window plus the unmeasured tester margin."""
        self._send = send
        self.frames = frames
        self.response_s = response_s  # the profile's window: what the device owes (search steps wait this)
        self.frame_s = FRAME_BITS / bitrate if bitrate else FRAME_S  # the least time from an answer to a request
        self._sent = frames.mark()  # the last request: the slave frames after it are the answers to keep clear of
        self.answer_timeout_s = answer_window(response_s)  # an expected answer is waited for this long
        self._windows = windows
        self._silence = False  # inside ``no_answer_expected``
        self.steps = 0  # frames sent (fastscan cost, for the report)
        self._requested: list[int] = []  # the command specifiers sent inside ``no_answer_expected``
        self.latencies: list[float] = []  # seconds each answer took
        self._several = False  # more than one slave answered the fastscan reset: wait for their copies

    # -- the exchange ------------------------------------------------------------------------------
    def request(self, command: int, payload: bytes = b"") -> Mark:
        """One master frame, at least ``frame_s`` after the last slave answer; a mark before it."""
        self._keep_clear_of_answers()
        mark = self.frames.mark()
        self._send(MASTER_COB_ID, bytes([command]) + payload.ljust(7, b"\x00")[:7])
        self._sent = mark
        self.steps += 1
        if self._silence:
            self._requested.append(command)
        return mark

    def _keep_clear_of_answers(self) -> None:
        """Wait what is left of one frame time after the latest slave frame since the last request (every
        answer counts, the copies of other slaves and late ones too): a computed remainder, not a fixed sleep."""
        answers = self.frames.since(self._sent, _from_slave)
        if not answers:
            return
        age = time.time() - answers[-1].timestamp
        if not 0.0 <= age <= HOST_STAMP_AGE_S:  # an adapter's own clock: the answer is only known to be here now
            age = 0.0
        remaining = self.frame_s - age
        if remaining > 0:
            with BUDGET.booking("silence"):  # the bus's frame time, owed in full
                time.sleep(remaining)

    @property
    def silence_s(self) -> float:
        """How long an answer that must not come is watched for (the device's LSS silence window, or without
        ``windows`` the profile's window plus the unmeasured tester margin)."""
        if self._windows is None:
            return self.response_s + UNMEASURED_MARGIN_S
        return self._windows.silence_s(LSS_FIGURE)

    @contextmanager
    def no_answer_expected(self, basis: str | None = None) -> Iterator[None]:
        """Within it, services wait ``silence_s`` for their answer instead of ``answer_timeout_s``: for checks
        that a request goes unanswered (only a silence costs the whole wait). With ``basis`` (the clause that
        forbids the answer; not for a probe whose later answer is fine), a slave frame after it and before the
        tester's next LSS request is still charged to the check (the late-frame ledger)."""
        saved, self._silence = self._silence, True
        outer, self._requested = self._requested, []
        try:
            yield
        finally:
            self._silence = saved
            requested = self._requested
            self._requested = outer + requested if saved else []  # an outer context's requests go on
        if basis is not None:
            self._forbid_answers(requested, basis)

    def _forbid_answers(self, requests: list[int], basis: str) -> None:
        """Declare the answers to ``requests`` (command specifiers) late from now until a request that may draw
        one of them (``late_frames.py``)."""
        answers = {answer_command(c) for c in requests} - {None}
        if not answers:
            return
        drawers = {c for c in LssCommand if answer_command(c) in answers}
        what = "an LSS answer " + "/".join(f"{a:02X}h" for a in sorted(a for a in answers if a is not None))
        self.frames.late.forbid(lambda m: _from_slave(m) and bool(m.data) and m.data[0] in answers, what,
                                "an LSS request that must stay unanswered", basis,
                                until=lambda m: m.arbitration_id == MASTER_COB_ID and bool(m.data)
                                and m.data[0] in drawers)

    def answer(self, command: int, mark: Mark, timeout: float | None = None) -> can.Message | None:
        """The first slave frame with ``command`` after ``mark``: within ``timeout``, else ``answer_timeout_s``
        (``silence_s`` inside ``no_answer_expected``). How long an answer took (on the host's clock, from the
        wait's start) is kept in ``latencies``."""
        if timeout is None:
            timeout = self.silence_s if self._silence else self.answer_timeout_s
        start = time.perf_counter()
        found = self.frames.wait_for(self._is_answer(command), timeout, mark)
        if found is not None:
            self.latencies.append(time.perf_counter() - start)
            if self._windows is not None:
                self._windows.observe(LSS_FIGURE, self.latencies[-1] * 1000)
        return found

    def learned_window(self, floor_s: float = WINDOW_FLOOR_S) -> float:
        """A response window from the answers seen so far: three times the slowest of the last 20, at least
        ``floor_s``, at most the profile's window (which it is before any answer)."""
        recent = self.latencies[-20:]
        if not recent:
            return self.response_s
        return min(self.response_s, max(floor_s, 3 * max(recent)))

    @staticmethod
    def _is_answer(command: int) -> Callable[[can.Message], bool]:
        return lambda m: _from_slave(m) and bool(m.data) and m.data[0] == command

    def answers(self, command: int, mark: Mark, window: float | None = None) -> list[can.Message]:
        """Every slave frame with ``command`` after ``mark``: with ``window``, those within it (waits the whole
        window); else the first as ``answer`` waits for it, and the others within the response window after it."""
        if window is None:
            if self.answer(command, mark) is None:
                return []
            window = self.response_s
        return self.frames.quiet_period(self._is_answer(command), window, mark)

    # -- state -------------------------------------------------------------------------------------
    def switch_global(self, state: LssState) -> Mark:
        """Switch state global (no answer)."""
        return self.request(LssCommand.SWITCH_STATE_GLOBAL, bytes([state]))

    def switch_selective(self, address: LssAddress) -> bool:
        """Switch state selective: the slave with ``address`` enters configuration state and answers 44h."""
        mark = self.frames.mark()
        for command, value in zip(SELECTIVE_COMMANDS, address.parts(), strict=True):
            self.request(command, struct.pack("<I", value))
        return self.answer(LssCommand.SWITCH_SELECTIVE_RESPONSE, mark) is not None

    # -- configuration -----------------------------------------------------------------------------
    def _configure(self, command: int, payload: bytes) -> LssAnswer | None:
        found = self.answer(command, self.request(command, payload))
        return None if found is None else LssAnswer(found.data[1], found.data[2])

    def configure_node_id(self, node_id: int) -> LssAnswer | None:
        return self._configure(LssCommand.CONFIGURE_NODE_ID, bytes([node_id]))

    def configure_bit_timing(self, index: int, table: int = 0) -> LssAnswer | None:
        return self._configure(LssCommand.CONFIGURE_BIT_TIMING, bytes([table, index]))

    def activate_bit_timing(self, switch_delay_ms: int) -> Mark:
        """Activate bit timing (no answer): silence for the delay, the new rate, silence again."""
        return self.request(LssCommand.ACTIVATE_BIT_TIMING, struct.pack("<H", switch_delay_ms))

    def store_configuration(self) -> LssAnswer | None:
        return self._configure(LssCommand.STORE_CONFIGURATION, b"")

    # -- inquiry -----------------------------------------------------------------------------------
    def inquire(self, part: str) -> int | None:
        """Vendor, product, revision or serial of the slave in configuration state."""
        command = INQUIRE_COMMANDS[ADDRESS_PARTS.index(part)]
        found = self.answer(command, self.request(command))
        return None if found is None else struct.unpack_from("<I", bytes(found.data), 1)[0]

    def inquire_address(self) -> LssAddress | None:
        parts = [self.inquire(part) for part in ADDRESS_PARTS]
        answered = [part for part in parts if part is not None]
        return LssAddress(*answered) if len(answered) == len(parts) else None

    def inquire_node_id(self) -> int | None:
        found = self.answer(LssCommand.INQUIRE_NODE_ID, self.request(LssCommand.INQUIRE_NODE_ID))
        return None if found is None else found.data[1]

    # -- identification ----------------------------------------------------------------------------
    def identify_remote(self, low: LssAddress, high: LssAddress) -> int:
        """Identify remote slaves: vendor and product exact, revision and serial in [low, high]; how many answered."""
        mark = self.frames.mark()
        values = (low.vendor, low.product, low.revision, high.revision, low.serial, high.serial)
        for command, value in zip(IDENTIFY_RANGE_COMMANDS, values, strict=True):
            self.request(command, struct.pack("<I", value))
        return len(self.answers(LssCommand.IDENTIFY_SLAVE, mark))

    def identify_non_configured(self) -> int:
        """How many non-configured slaves (node-ID FFh) answered."""
        mark = self.request(LssCommand.IDENTIFY_NON_CONFIGURED)
        return len(self.answers(LssCommand.IDENTIFY_NON_CONFIGURED_SLAVE, mark))

    # -- fastscan ----------------------------------------------------------------------------------
    def _fastscan_step(self, id_number: int, bit_checked: int, sub: int, next_sub: int) -> bool:
        mark = self.request(LssCommand.FASTSCAN, struct.pack("<IBBB", id_number, bit_checked, sub, next_sub))
        if self.answer(LssCommand.IDENTIFY_SLAVE, mark, self.response_s) is None:  # silence means a 1 bit
            return False
        if self._several:
            self.frames.quiet_period(lambda m: False, ECHO_S)  # the other slaves' copies land before the next step
        return True

    def fastscan_learned(self, known: Sequence[int | None] = (None, None, None, None)) -> LssAddress | None:
        """Fastscan whose steps wait the window learned from this slave's answers (``learned_window``); if that
        finds nobody (a step that waited too briefly makes the confirm fail: a wrong address is never
        returned), once more with the full window."""
        saved, learned = self.response_s, self.learned_window()
        if learned >= saved:
            return self.fastscan(known)
        self.response_s = learned
        try:
            found = self.fastscan(known)
        finally:
            self.response_s = saved
        return found if found is not None else self.fastscan(known)

    def fastscan(self, known: Sequence[int | None] = (None, None, None, None),
                 guess: Sequence[int | None] = (None, None, None, None)) -> LssAddress | None:
        """CiA 305 fastscan: the address of one non-configured slave, which is then in configuration state;
        None when no slave answers. Parts given in ``known`` (e.g. vendor and product from the profile) are
        confirmed in one step instead of 32. A part in ``guess`` (e.g. the previous slave's) is tried in one
        step first; if no slave has it, none moved on and that part is scanned bit by bit as usual."""
        self._several = False
        mark = self.request(LssCommand.FASTSCAN, struct.pack("<IBBB", 0, FASTSCAN_RESET_BIT, 0, 0))
        if self.answer(LssCommand.IDENTIFY_SLAVE, mark, self.response_s) is None:  # a scan's own late-answer rules
            return None
        self._several = len(self.answers(LssCommand.IDENTIFY_SLAVE, mark, ECHO_S)) > 1
        address: list[int] = []
        for sub in range(4):
            value, guessed = known[sub], guess[sub]
            if value is None and guessed is not None and self._fastscan_step(guessed, 0, sub, (sub + 1) % 4):
                address.append(guessed)
                continue
            if value is None:
                value = 0
                for bit in range(31, -1, -1):
                    if not self._fastscan_step(value, bit, sub, sub):  # nobody has 0 there: it is 1
                        value |= 1 << bit
            if not self._fastscan_step(value, 0, sub, (sub + 1) % 4):
                return None  # a known part was wrong, or the slave left the scan
            address.append(value)
        return LssAddress(*address)


def _from_slave(msg: can.Message) -> bool:
    """A frame an LSS slave sent (7E4h, received)."""
    return bool(msg.is_rx) and msg.arbitration_id == SLAVE_COB_ID
