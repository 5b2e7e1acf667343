"""Words for the SDO frames a verdict judged: the request as the protocol reads it, each reply with its time.

A failure names the request and every reply it judged (CiA 301 §7.2.4.3): "segmented download 2000h.00, 12 bytes",
then "confirmed (20 00 00 00 00 00 00 00), then 0.013 ms later abort 06070010h (...)". A reply keeps the tester's
receive timestamp (``Stamped``) so that the gap between two answers can be said. Used by the SDO fuzzer and the
protocol checks.
"""

from __future__ import annotations

import struct

from encoder_conformance.cia.cia301 import SDO_ABORT
from encoder_conformance.dut.sdo.sdo_frames import abort_name


class Stamped(bytes):
    """A frame's data with the timestamp the tester's log gives it (None where not known): the interface's receive
    stamp for a reply, the tester's clock just before sending for a request."""

    at: float | None

    def __new__(cls, data: bytes, at: float | None = None) -> Stamped:
        frame = super().__new__(cls, data)
        frame.at = at
        return frame


def _hex(data: bytes) -> str:
    return data.hex(" ").upper() or "(no data)"


def _mux(frame: bytes) -> str:
    index, sub = struct.unpack_from("<HB", frame, 1)
    return f"{index:04X}h.{sub:02X}"


def _initiate(frame: bytes) -> str:
    command = frame[0]
    if command >> 5 == 2:
        return f"upload {_mux(frame)}" + (f" (reserved bits {command & 0x1F:02X}h)" if command & 0x1F else "")
    if command & 0x02:
        count = 4 - (command >> 2 & 0x03) if command & 0x01 else "unstated"
        return f"expedited download {_mux(frame)}, {count} bytes"
    size = f"{struct.unpack_from('<I', frame, 4)[0]} bytes" if command & 0x01 else "size not indicated"
    return f"segmented download {_mux(frame)}, {size}"


def _segment(frame: bytes) -> str:
    command, toggle = frame[0], frame[0] >> 4 & 1
    if command >> 5 == 3:
        return f"upload segment request, toggle {toggle}"
    return (f"download segment, toggle {toggle}, {7 - (command >> 1 & 0x07)} bytes"
            + (", the last" if command & 0x01 else ""))


def request(frame: bytes) -> str:
    """What a request frame asks, as the protocol reads it, with its bytes: 'upload 1000h.00 (40 00 10 ...)'."""
    ccs, length = (frame[0] >> 5 if frame else None), len(frame)
    if length < 8:
        carried = f"; it carries {_mux(frame)}" if length >= 4 and ccs in (1, 2) else ""
        return f"a frame of {length} bytes ({_hex(frame)}{carried})"
    if ccs in (1, 2):
        what = _initiate(frame)
    elif ccs in (0, 3):
        what = _segment(frame)
    elif ccs == 4:
        what = f"abort transfer {_mux(frame)} (from the client)"
    else:
        what = f"command specifier {ccs}"
    return f"{what} ({_hex(frame)})"


def reply(data: bytes) -> str:
    """One reply as the protocol reads it: 'abort 06070010h (...) naming 2000h.00' or 'confirmed (60 ...)'."""
    if len(data) == 8 and data[0] == SDO_ABORT:
        return f"abort {abort_name(struct.unpack_from('<I', data, 4)[0])} naming {_mux(data)}"
    if len(data) == 8 and data[0] >> 5 in (1, 3):
        return f"confirmed ({_hex(data)})"
    return f"answered {_hex(data)}"


def replies(data: list[bytes]) -> str:
    """Every reply in order, each after the one before with the time between them where both are known."""
    parts: list[str] = []
    for n, frame in enumerate(data):
        text = reply(frame)
        before = data[n - 1] if n else None
        gap = _gap(before, frame)
        if before is not None:
            text = f"then{'' if gap is None else f' {gap * 1000:.3f} ms later'} {text}"
        parts.append(text)
    return ", ".join(parts)


def _gap(earlier: bytes | None, later: bytes) -> float | None:
    first, then = getattr(earlier, "at", None), getattr(later, "at", None)
    return None if first is None or then is None else then - first
