"""Hypothesis strategies for SDO request sequences a device must survive (CiA 301 §7.2.4.3).

An example is a short tuple of request frames (``Request``), sent in order. What is generated is
harmless on a bench by construction:

- uploads of anything (any index, sub-index and reserved bits);
- expedited downloads only to entries that must refuse them: declared ro/const entries and indices
  in CiA 301's reserved areas (0000h-0FFFh, C000h-FFFFh), never an undeclared index in the areas where
  a manual may have left a manufacturer or profile object out;
- segmented download initiates (nothing is written before the last segment) also to writable entries,
  whose segments never carry the last-segment bit;
- never a download of any kind to the exclusion list (``exclusions.never_write``) or to an entry the device
  stores by itself (``exclusions.self_storing``), not even a block download initiate (ccs 6) where the
  profile has no block transfer;
- truncated frames (DLC < 8) only as truncations of the above.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from functools import cache

from hypothesis import strategies as st

from encoder_conformance.cia.cia301 import SDO_ABORT
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.schema import DeviceProfile

Mux = tuple[int, int]
#: CiA 301 §7.4.1 index areas in which no object can be writable: data types and the reserved area
RESERVED_AREAS = ((0x0000, 0x0FFF), (0xC000, 0xFFFF))
CLIENT_ABORT = SDO_ABORT


@dataclass(frozen=True)
class Request:
    """One SDO request frame; ``refused``: CiA 301 says the device must abort it (a write it must refuse)."""

    frame: bytes
    refused: bool = False

    def __str__(self) -> str:
        return f"[{len(self.frame)}] {self.frame.hex(' ').upper()}" + (" (must be refused)" if self.refused else "")


Example = tuple[Request, ...]


@dataclass(frozen=True)
class Targets:
    """What the profile lets the fuzzer address."""

    declared: tuple[Mux, ...]
    refusing: tuple[Mux, ...]  # ro/const entries outside the exclusion list: writes must be aborted
    writable: tuple[Mux, ...]  # readable rw entries outside the exclusion list: segmented initiates only
    long: tuple[Mux, ...]  # readable entries over 4 bytes: their upload is segmented
    indices: tuple[int, ...]
    block_sdo: bool
    forbidden: frozenset[int] = frozenset()  # indices no download may name
    self_storing: frozenset[Mux] = frozenset()  # entries no download may name

    @classmethod
    def of(cls, profile: DeviceProfile, excluded: dict[int, str], self_storing: frozenset[Mux]) -> Targets:
        entries = [(i, s, e) for i, s, _, e in profile.iter_entries()]
        allowed = [(i, s, e) for i, s, e in entries if i not in excluded and (i, s) not in self_storing]
        return cls(
            declared=tuple((i, s) for i, s, _ in entries),
            refusing=tuple((i, s) for i, s, e in allowed if e.access in ("ro", "const")),
            writable=tuple((i, s) for i, s, e in allowed if e.access in ("rw", "rwr", "rww")),
            long=tuple((i, s) for i, s, e in entries if e.access != "wo" and (datatypes.size_bytes(e.type) or 8) > 4),
            indices=tuple(sorted(profile.objects)),
            block_sdo=profile.capabilities.block_sdo,
            forbidden=frozenset(excluded),
            self_storing=self_storing,
        )

    def may_download(self, frame: bytes) -> bool:
        """False for a frame that a device would take as a download to an excluded or self-storing entry."""
        if len(frame) < 4 or frame[0] >> 5 not in (1, 6):
            return True
        index, sub = struct.unpack_from("<HB", frame, 1)
        return index not in self.forbidden and (index, sub) not in self.self_storing


@cache  # strategies are built once per profile: building one per draw costs more than the draw
def _reserved_mux() -> st.SearchStrategy[Mux]:
    areas = [st.integers(low, high) for low, high in RESERVED_AREAS]
    return st.tuples(st.one_of(areas), st.integers(0, 0xFF))


@cache
def _any_mux(targets: Targets) -> st.SearchStrategy[Mux]:
    return st.one_of(
        st.sampled_from(targets.declared),
        st.tuples(st.sampled_from(targets.indices), st.integers(0, 0xFF)),
        st.tuples(st.integers(0, 0xFFFF), st.integers(0, 0xFF)),
    )


@cache
def _refusing_mux(targets: Targets) -> st.SearchStrategy[Mux]:
    return st.one_of(_reserved_mux(), *([st.sampled_from(targets.refusing)] if targets.refusing else []))


def _frame(command: int, mux: Mux, tail: bytes) -> bytes:
    return struct.pack("<BHB", command, *mux) + tail


@cache
def upload_initiates(targets: Targets) -> st.SearchStrategy[Request]:
    """ccs 2 with any reserved bits, any multiplexer, any reserved bytes."""
    return st.builds(lambda low, mux, tail: Request(_frame(0x40 | low, mux, tail)),
                     st.integers(0, 0x1F), _any_mux(targets), st.binary(min_size=4, max_size=4))


@cache
def expedited_downloads(targets: Targets) -> st.SearchStrategy[Request]:
    """ccs 1 with e=1 and any n/s bits, to entries that must refuse the write."""
    return st.builds(lambda n, s, mux, data: Request(_frame(0x22 | n << 2 | s, mux, data), refused=True),
                     st.integers(0, 3), st.integers(0, 1), _refusing_mux(targets), st.binary(min_size=4, max_size=4))


@cache
def segmented_download_initiates(targets: Targets) -> st.SearchStrategy[Request]:
    """ccs 1 with e=0 (any n/s bits, any size): opens a transfer, writes nothing yet."""
    muxes = st.one_of(_refusing_mux(targets), *([st.sampled_from(targets.writable)] if targets.writable else []))
    return st.builds(lambda n, s, mux, size: Request(_frame(0x20 | n << 2 | s, mux, size)),
                     st.integers(0, 3), st.integers(0, 1), muxes, st.binary(min_size=4, max_size=4))


@cache
def initiates(targets: Targets) -> st.SearchStrategy[Request]:
    """Any initiate request the fuzzer may send."""
    return st.one_of(upload_initiates(targets), expedited_downloads(targets), segmented_download_initiates(targets))


@cache
def reserved_commands(targets: Targets) -> st.SearchStrategy[Request]:
    """ccs 7 (and 5, 6 where the profile has no block transfer) with any other bytes."""
    ccs = [7] if targets.block_sdo else [5, 6, 7]
    frames = st.builds(lambda c, low, rest: Request(bytes([c << 5 | low]) + rest),
                       st.sampled_from(ccs), st.integers(0, 0x1F), st.binary(min_size=7, max_size=7))
    return frames.filter(lambda r: targets.may_download(r.frame))  # ccs 6 is a block download initiate


def truncated(requests: st.SearchStrategy[Request]) -> st.SearchStrategy[Request]:
    """A harmless request cut to 0..7 bytes (a write that must be refused stays one where its bytes are served)."""
    return st.builds(lambda r, length: Request(r.frame[:length], r.refused), requests, st.integers(0, 7))


def client_abort(mux: Mux, code: int) -> Request:
    return Request(struct.pack("<BHBI", CLIENT_ABORT, *mux, code))


def _segment(upload: bool, toggle: int, low: int, data: bytes, last_allowed: bool) -> Request:
    if upload:
        return Request(bytes([0x60 | toggle << 4 | (low & 0x0F)]) + data)
    last = low & 1 if last_allowed else 0
    return Request(bytes([toggle << 4 | (low & 0x0E) | last]) + data)


@cache
def _long_mux(targets: Targets) -> st.SearchStrategy[Mux]:
    return st.sampled_from(targets.long) if targets.long else _any_mux(targets)


OPENINGS = st.sampled_from(["none", "upload", "download"])
BITS, NIBBLES, SEGMENT_DATA = st.integers(0, 1), st.integers(0, 0x0F), st.binary(min_size=7, max_size=7)


@st.composite
def _opening(draw: st.DrawFn, targets: Targets, choices: st.SearchStrategy[str] = OPENINGS
             ) -> tuple[Request | None, bool]:
    """A transfer-opening initiate (or none), and whether its download segments may carry the last bit."""
    choice = draw(choices)
    if choice == "upload":
        return Request(_frame(0x40, draw(_long_mux(targets)), bytes(4))), True
    if choice == "download":
        initiate = draw(segmented_download_initiates(targets))
        mux = struct.unpack_from("<HB", initiate.frame, 1)
        return initiate, mux not in targets.writable
    return None, True


def _segments(draw: st.DrawFn, last_allowed: bool, count: st.SearchStrategy[int]) -> list[Request]:
    return [_segment(bool(draw(BITS)), draw(BITS), draw(NIBBLES), draw(SEGMENT_DATA), last_allowed)
            for _ in range(draw(count))]


SEGMENT_COUNT, INTERLEAVED_COUNT = st.integers(1, 4), st.integers(1, 3)


@st.composite
def segment_sequences(draw: st.DrawFn, targets: Targets) -> Example:
    """Segments without an initiate, of the wrong direction, with toggles out of order, or after an abort."""
    opening, last_allowed = draw(_opening(targets))
    steps = [opening] if opening else []
    steps += _segments(draw, last_allowed, SEGMENT_COUNT)
    if draw(BITS) and opening:
        mux = struct.unpack_from("<HB", opening.frame, 1)
        position = draw(st.integers(1, len(steps)))
        steps.insert(position, client_abort(mux, int.from_bytes(draw(SEGMENT_DATA)[:4], "little")))
    return tuple(steps)


TRANSFERS = st.sampled_from(["upload", "download"])


@st.composite
def interleaved_transfers(draw: st.DrawFn, targets: Targets) -> Example:
    """Two initiates, then segments meant for the first one (toggle from 0, in order)."""
    first, last_allowed = draw(_opening(targets, TRANSFERS))
    second = draw(initiates(targets))
    assert first is not None
    upload = first.frame[0] >> 5 == 2
    segments = [_segment(upload, n % 2, 0, draw(SEGMENT_DATA), last_allowed) for n in range(draw(INTERLEAVED_COUNT))]
    return (first, second, *segments)
