"""What a device's SDO answers to a fuzz example must look like (CiA 301 §7.2.4.3): a pure judge, no I/O.

Per request: a DLC-8 request other than an abort (ccs 4) gets exactly one reply; a client's abort gets
none; a frame shorter than 8 bytes gets none, one abort (any multiplexer), or the answer to the request its bytes
carry (open readings sdo-short-frame, sdo-short-frame-served: ``carries_request``, judged as that request). Every
reply has DLC 8 and the server command specifier that answers the request, or is an abort (command byte 80h).
Initiate requests (ccs 1, 2) are answered, also when aborted, with their multiplexer; one with bits set that
CiA 301 says are always 0 may instead be refused as an invalid command, abort 05040001h with any multiplexer (open
reading sdo-initiate-reserved-bits: ``sdo_frames.refused_as_invalid``). An abort during a segmented transfer carries the
transfer's multiplexer. Segments outside a transfer, of the other direction or with the toggle bit not
alternated are aborted; a segment response echoes the toggle bit.

The judge follows the transfer the device has open, as far as its answers tell. Where they do not
(an initiate aborted while a transfer was open: the device may go on with the old one), the state is
unknown and segments are judged only as frames. An initiate while a transfer is open may draw an abort
naming the open transfer first (either side may abort at any time, CiA 301 §7.2.4.2), then its own
answer, or that abort alone (the request taken as a wrong frame of the open transfer): open readings
sdo-request-while-transfer-open and sdo-request-taken-by-open-transfer.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import pairwise

from encoder_conformance.cia.cia301 import SDO_ABORT, SdoClientCommand
from encoder_conformance.dut.sdo import sdo_words
from encoder_conformance.dut.sdo.sdo_frames import ABORT_SCS, ANSWER_SCS, answers, refused_as_invalid, reserved_bits_set
from encoder_conformance.fuzz.strategies import Request

ABORT = SDO_ABORT
SEGMENT_CCS = (SdoClientCommand.DOWNLOAD_SEGMENT, SdoClientCommand.UPLOAD_SEGMENT)
INITIATE_CCS = (SdoClientCommand.INITIATE_DOWNLOAD, SdoClientCommand.INITIATE_UPLOAD)


@dataclass(frozen=True)
class Transfer:
    """A segmented transfer the device has open: its direction, multiplexer and the next toggle bit."""

    upload: bool
    mux: bytes
    toggle: int = 0


UNKNOWN = "unknown"  # the device's transfer state cannot be told from its answers


@dataclass
class Exchange:
    """A request and every reply attributed to it."""

    request: Request
    replies: list[bytes] = field(default_factory=list)


def _ccs(frame: bytes) -> int | None:
    return frame[0] >> 5 if frame else None


def reply_required(frame: bytes) -> bool:
    return len(frame) == 8 and _ccs(frame) != 4


def no_reply_expected(frame: bytes) -> bool:
    """A client's abort or a short frame: nothing (or, for a short frame, an abort) comes back."""
    return not reply_required(frame)


def fits(frame: bytes, reply: bytes) -> bool:
    """A reply that can only be the answer to this request (a known command and, for initiates, its multiplexer)."""
    return len(frame) == 8 and _ccs(frame) in ANSWER_SCS and answers(frame, reply)


def _hex(data: bytes) -> str:
    return data.hex(" ").upper() or "(no data)"


def carries_request(frame: bytes) -> bool:
    """A frame under 8 bytes whose bytes still hold what its request needs (CiA 301 §7.2.4.3.3-§7.2.4.3.7): an
    initiate its multiplexer (a download's missing data or size bytes read as 0, or bounded by the frame's length:
    a stack seen took a 6-byte initiate download as one), a download segment the data its n announces, an upload
    segment or a reserved command specifier its command byte, a client's abort its code."""
    if not frame:
        return False
    ccs = frame[0] >> 5
    needed: dict[int, int] = {
        SdoClientCommand.INITIATE_UPLOAD: 4,
        SdoClientCommand.INITIATE_DOWNLOAD: 4,
        SdoClientCommand.DOWNLOAD_SEGMENT: 8 - (frame[0] >> 1 & 0x07),
        SdoClientCommand.ABORT: 8,
    }
    return len(frame) >= needed.get(ccs, 1)


def _spare_reply_at(exchanges: list[Exchange]) -> int | None:
    """The first exchange holding a reply too many (two, or one its request does not owe), where every one before
    it holds exactly the one it owes; else None."""
    for n, exchange in enumerate(exchanges):
        if len(exchange.replies) >= 2 or (exchange.replies and not reply_required(exchange.request.frame)):
            return n
        if len(exchange.replies) != 1:
            return None
    return None


def _hole_at(exchanges: list[Exchange]) -> int | None:
    """The first exchange without the reply its request owes, where every one before it holds exactly one; else
    None."""
    for n, exchange in enumerate(exchanges):
        if not exchange.replies and reply_required(exchange.request.frame):
            return n
        if len(exchange.replies) != 1:
            return None
    return None


class Judge:
    """Judges the exchanges of one example after another, carrying the device's transfer state."""

    def __init__(self, block_sdo: bool = False) -> None:
        self.block_sdo = block_sdo
        self.transfer: Transfer | str | None = None

    def judge(self, exchanges: list[Exchange]) -> list[str]:
        problems: list[str] = []
        for n, exchange in enumerate(exchanges):
            rest = exchanges[n + 1 :]
            if len(exchange.replies) == 1 and rest:
                self._pull_back_late_answer(exchange, rest)
            problems += [f"{sdo_words.request(exchange.request.frame)}: {p}" for p in self._one(exchange, rest)]
        return problems

    def _pull_back_late_answer(self, exchange: Exchange, rest: list[Exchange]) -> None:
        """An initiate about the open transfer's own entry drew an abort naming it, and its answer came after the
        next request was sent (so it went to that one): where a later request holds a reply too many (two, or one
        it does not owe), each reply on the way moves back by one request (the device answers in order). Without
        such a spare reply every request has its own answer: the initiate was taken by the open transfer."""
        frame, first = exchange.request.frame, exchange.replies[0]
        same_entry = isinstance(self.transfer, Transfer) and frame[1:4] == self.transfer.mux
        if not same_entry or not rest[0].replies or not self._ends_open_transfer(frame, first, answered=True):
            return
        late = rest[0].replies[0]
        if late == first or not fits(frame, late):
            return  # the same frame twice is a second reply, not an answer
        spare = _spare_reply_at(rest)
        if spare is None:
            return
        exchange.replies.append(rest[0].replies.pop(0))
        for earlier, later in pairwise(rest[: spare + 1]):
            earlier.replies.append(later.replies.pop(0))

    def _ends_open_transfer(self, frame: bytes, reply: bytes, answered: bool = False) -> bool:
        """An abort naming the open transfer in answer to an initiate about another entry, or about the same one
        where an answer follows (``answered``; see the docstring)."""
        transfer = self.transfer
        return (isinstance(transfer, Transfer) and len(frame) == 8 and _ccs(frame) in INITIATE_CCS
                and (frame[1:4] != transfer.mux or answered) and len(reply) == 8 and reply[0] == ABORT
                and reply[1:4] == transfer.mux)

    def _one(self, exchange: Exchange, rest: list[Exchange] | None = None) -> list[str]:
        rest = rest or []
        frame, replies = exchange.request.frame, exchange.replies
        if replies and self._ends_open_transfer(frame, replies[0], answered=len(replies) > 1):
            self.transfer = None
            replies = replies[1:]
            if not replies:
                return []  # taken as a wrong frame of the open transfer: the request itself is not answered
        if len(frame) < 8:
            return self._short(exchange.request, replies)
        if _ccs(frame) == 4:
            self.transfer = None
            return [f"{len(replies)} repl{'y' if len(replies) == 1 else 'ies'} to an abort transfer request, which "
                    f"CiA 301 leaves unconfirmed: {sdo_words.replies(replies)}"] if replies else []
        if not replies:
            return ["no reply (CiA 301: every SDO request but an abort is confirmed)"]
        judged = self._reply(exchange.request, replies[0])
        following = rest[0] if rest else None
        if len(replies) > 1 and following is not None and all(
                self._ends_open_transfer(following.request.frame, extra, bool(following.replies))
                for extra in replies[1:]):
            moved = replies[1:]  # the abort that ended the open transfer came for the next initiate
            following.replies[:0] = moved
            del exchange.replies[-len(moved):]
            replies = replies[:1]
            hole = _hole_at(rest[1:]) if len(following.replies) == 2 else None
            if hole is not None:  # that initiate was taken by the open transfer: the replies after it move on by one
                carry = following.replies.pop()
                for later in rest[1 : hole + 2]:
                    later.replies.insert(0, carry)
                    if len(later.replies) > 1:
                        carry = later.replies.pop()
        problems = [f"{len(replies)} replies to one request: {sdo_words.replies(replies)} (CiA 301: one confirmation "
                    "or one abort per request)"][: len(replies) - 1]
        return problems + judged

    def _short(self, request: Request, replies: list[bytes]) -> list[str]:
        """Ignored, one abort (any multiplexer), or served as the request its bytes carry (see the docstring)."""
        frame = request.frame
        if not replies:
            return []
        if len(replies) > 1:
            return [f"{len(replies)} replies to a frame shorter than 8 bytes: {sdo_words.replies(replies)} (ignored, "
                    "one abort or one answer: open readings sdo-short-frame, sdo-short-frame-served)"]
        reply = replies[0]
        if len(reply) == 8 and reply[0] == ABORT:
            self.transfer = None
            return []
        if not carries_request(frame):
            return [f"a frame shorter than 8 bytes is answered with {_hex(reply)}, though its bytes do not carry "
                    "the request (CiA 301 §7.2.4.3.1: SDO frames have 8 data bytes; a shorter one is ignored, aborted "
                    "or served as the request it carries: open readings sdo-short-frame, sdo-short-frame-served)"]
        served = Request(frame.ljust(8, b"\x00"), request.refused)
        return [f"served as {sdo_words.request(served.frame)}: {p}" for p in self._reply(served, reply)]

    def _reply(self, request: Request, reply: bytes) -> list[str]:
        frame = request.frame
        ccs = frame[0] >> 5
        if len(reply) != 8:
            self.transfer = UNKNOWN
            return [f"reply {_hex(reply)} has DLC {len(reply)}, not 8"]
        if reply[0] >> 5 == ABORT_SCS:
            return self._abort(frame, ccs, reply)
        expected = ANSWER_SCS.get(ccs) if ccs in (*SEGMENT_CCS, *INITIATE_CCS) else None
        if expected is None or reply[0] >> 5 != expected:
            self.transfer = UNKNOWN
            return [f"reply {_hex(reply)}: server command {reply[0] >> 5} does not answer client command {ccs}"
                    + (" (only an abort does)" if expected is None else f" (expected {expected} or an abort)")]
        if request.refused:
            self.transfer = None
            return [f"confirmed ({_hex(reply)}) a write CiA 301 says must be refused (read-only or no object)"]
        if ccs in INITIATE_CCS:
            return self._initiated(frame, reply)
        return self._segment(frame, ccs, reply)

    def _abort(self, frame: bytes, ccs: int, reply: bytes) -> list[str]:
        problems = [f"abort {_hex(reply)}: the command byte of an abort is 80h"] if reply[0] != ABORT else []
        transfer = self.transfer
        if ccs in INITIATE_CCS:
            if reply[1:4] != frame[1:4] and not refused_as_invalid(frame, reply):
                problems.append(f"abort {_hex(reply)} does not echo the request's multiplexer {_hex(frame[1:4])}"
                                + (" (only 05040001h, refusing it as an invalid command, may name another)"
                                   if reserved_bits_set(frame) else ""))
            self.transfer = UNKNOWN if transfer is not None else None  # the open transfer may go on
        elif ccs in SEGMENT_CCS and isinstance(transfer, Transfer) and reply[1:4] != transfer.mux:
            problems.append(f"abort {_hex(reply)} during the transfer of {_hex(transfer.mux)} does not carry its "
                            "multiplexer")
            self.transfer = None
        else:
            self.transfer = None
        return problems

    def _initiated(self, frame: bytes, reply: bytes) -> list[str]:
        if reply[1:4] != frame[1:4]:
            self.transfer = UNKNOWN
            return [f"reply {_hex(reply)} does not echo the request's multiplexer {_hex(frame[1:4])}"]
        upload = frame[0] >> 5 == 2
        segmented = not reply[0] & 0x02 if upload else not frame[0] & 0x02
        self.transfer = Transfer(upload, reply[1:4]) if segmented else None
        return []

    def _segment(self, frame: bytes, ccs: int, reply: bytes) -> list[str]:
        transfer, toggle = self.transfer, (frame[0] >> 4) & 1
        if transfer == UNKNOWN:
            return []
        if not isinstance(transfer, Transfer) or transfer.upload != (ccs == 3):
            self.transfer = UNKNOWN
            what = "no transfer is open" if transfer is None else "the open transfer goes the other way"
            return [f"segment answered with {_hex(reply)} although {what} (expected an abort)"]
        if toggle != transfer.toggle:
            self.transfer = UNKNOWN
            return [f"segment with toggle {toggle} (expected {transfer.toggle}) answered with {_hex(reply)}, not "
                    "aborted (CiA 301: toggle bit not alternated)"]
        if (reply[0] >> 4) & 1 != toggle:
            self.transfer = UNKNOWN
            return [f"segment response {_hex(reply)} does not echo the toggle bit {toggle}"]
        last = reply[0] & 1 if transfer.upload else frame[0] & 1
        self.transfer = None if last else Transfer(transfer.upload, transfer.mux, toggle ^ 1)
        return []
