"""Which request each SDO reply answers, from the bus order of requests and replies.

An SDO server answers its requests in order, so a reply belongs to a request sent before it and
not before the request the previous reply answered. Among those, a reply goes to the earliest
request it can only be the answer to (its command and, for initiates, its multiplexer, or for an initiate with
reserved bits set the 05040001h that refuses it, naming any: ``oracle.fits``);
else to the earliest that may draw an odd answer (a short frame, a client's abort, a reserved command);
requests still without a reply first. A reply that fits only answered requests is counted against the
earliest of them: that is how two replies to one request show, unless an earlier short frame or abort
request went without one (then the first of the two was its answer).
"""

from __future__ import annotations

from collections.abc import Sequence

from encoder_conformance.fuzz.oracle import Exchange, fits, reply_required
from encoder_conformance.fuzz.strategies import Request

Event = tuple[bool, bytes]  # (sent by the tester, data)


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


def attribute(requests: Sequence[Request], events: Sequence[Event]) -> tuple[list[Exchange], list[bytes]]:
    """The exchanges (each request with its replies) and the replies that came before any request."""
    exchanges = [Exchange(r) for r in requests]
    stray: list[bytes] = []
    sent = 0  # requests on the bus so far
    first_open = 0  # replies before this request's were all attributed
    for from_tester, data in events:
        if from_tester:
            sent = min(sent + 1, len(exchanges))
            continue
        if sent == 0:
            stray.append(data)
            continue
        target = _target(exchanges, range(first_open, sent), data)
        exchanges[target].replies.append(data)
        first_open = target
    _give_back_to_unanswered(exchanges)
    return exchanges, stray


def _give_back_to_unanswered(exchanges: list[Exchange]) -> None:
    """Two replies that fit one request, and an earlier short frame or abort request without one: the first
    reply was the answer to that frame (the device answers in order, and a frame cut short can look like the
    next request)."""
    for i, exchange in enumerate(exchanges):
        if len(exchange.replies) < 2:
            continue
        earlier = next((e for e in reversed(exchanges[:i]) if not e.replies and _loose(e.request.frame)), None)
        if earlier is not None:
            earlier.replies.append(exchange.replies.pop(0))
