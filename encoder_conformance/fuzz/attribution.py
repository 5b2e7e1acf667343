"""Which request each SDO reply answers, from the bus order of requests and replies.

An SDO server answers its requests in order, so a reply belongs to a request sent before it and
not before the request the previous reply answered. Among those, a reply goes to the earliest
request it can only be the answer to (its command and, for initiates, its multiplexer, or for an initiate with
reserved bits set the 05040001h that refuses it, naming any: ``oracle.fits``);
else to the earliest that may draw an odd answer (a short frame, a client's abort, a reserved command);
requests still without a reply first. A reply that fits only answered requests is counted against the
earliest of them: that is how two replies to one request show, unless an earlier short frame or abort
request went without one (then the first of the two was its answer).

Where the frames carry timestamps of one clock (``stamped``: the tester's host clock for its own frames, and
the interface's host or kernel stamp for received ones), a reply stamped before a request was sent answers an
earlier request, whatever order the tester's log shows them in: the log takes a reply in when the receiving
thread gets to it, the timestamp says when it came (an abort 13 µs after a confirmation is the same request's
second answer, though the tester sent its next request in between).
"""

from __future__ import annotations

from collections.abc import Sequence

from encoder_conformance.fuzz.oracle import Exchange, fits, reply_required
from encoder_conformance.fuzz.strategies import Request

Event = tuple[bool, bytes]  # (sent by the tester, data: a ``sdo_words.Stamped`` where the time is known)


def _loose(frame: bytes) -> bool:
    """A request whose reply, if any, cannot be told by its content."""
    return not reply_required(frame) or frame[0] >> 5 not in (0, 1, 2, 3)


def _target(exchanges: list[Exchange], window: range, reply: bytes) -> int:
    """The request ``reply`` answers, in order of preference (see the module docstring)."""
    tests = (
        lambda e: not e.replies and fits(e.request.frame, reply),
        lambda e: not e.replies and _loose(e.request.frame),
        lambda e: fits(e.request.frame, reply),  # a second reply
        lambda e: _loose(e.request.frame),
        lambda e: not e.replies,
    )
    for test in tests:
        found = next((i for i in window if test(exchanges[i])), None)
        if found is not None:
            return found
    return window.start


def _sent_before(sent_at: list[float | None], logged: int, reply: bytes) -> int:
    """How many requests were sent before ``reply`` came: those logged before it, less the ones whose send stamp is
    later than its receive stamp."""
    at = getattr(reply, "at", None)
    while at is not None and logged > 0 and (sent := sent_at[logged - 1]) is not None and sent > at:
        logged -= 1
    return logged


def attribute(requests: Sequence[Request], events: Sequence[Event],
              stamped: bool = False) -> tuple[list[Exchange], list[bytes]]:
    """The exchanges (each request with its replies) and the replies that came before any request; ``stamped``:
    the events' timestamps (``sdo_words.Stamped``) are of one clock and say the order."""
    exchanges = [Exchange(r) for r in requests]
    stray: list[bytes] = []
    sent_at: list[float | None] = []  # the send stamp of each request on the bus so far
    first_open = 0  # replies before this request's were all attributed
    floor = 0  # requests a reply has gone to so far, the last included
    for from_tester, data in events:
        if from_tester:
            if len(sent_at) < len(exchanges):
                sent_at.append(getattr(data, "at", None) if stamped else None)
            continue
        sent = _sent_before(sent_at, len(sent_at), data) if stamped else len(sent_at)
        sent = max(sent, floor)  # the device answers in order: never before the request the last reply answered
        if sent == 0:
            stray.append(data)
            continue
        target = _target(exchanges, range(first_open, sent), data)
        exchanges[target].replies.append(data)
        first_open, floor = target, target + 1
    _give_back_to_unanswered(exchanges)
    return exchanges, stray


def _give_back_to_unanswered(exchanges: list[Exchange]) -> None:
    """Two replies that fit one request, and an earlier short frame or abort request without one: the first
    reply was the answer to that frame (the device answers in order, and a frame cut short can look like the
    next request). A short frame (which may draw an answer) takes it before a client's abort (which may not): the
    abort to a short frame that came after the closing abort went out is the short frame's, not the abort's."""
    for i, exchange in enumerate(exchanges):
        if len(exchange.replies) < 2:
            continue
        waiting = [e for e in reversed(exchanges[:i]) if not e.replies and _loose(e.request.frame)]
        earlier = next((e for e in waiting if len(e.request.frame) < 8), waiting[0] if waiting else None)
        if earlier is not None:
            earlier.replies.append(exchange.replies.pop(0))
