"""An in-memory object dictionary and SDO frame builders for the twin's SDO server self-tests (shared helper)."""

from __future__ import annotations

import struct

from encoder_conformance.sim.engine.sdo_server import SdoAbort

NO_OBJECT = 0x06020000
WRITE_RO = 0x06010002
TOGGLE = 0x05030000
COMMAND_INVALID = 0x05040001
LENGTH_MISMATCH = 0x06070010

TEXT = b"ABCDEFGHIJKLMNOPQRST"  # 20 bytes: segments of 7, 7 and 6


class FakeAccess:
    """In-memory objects; 0x1000 is read-only, anything unknown aborts 06020000h."""

    def __init__(self) -> None:
        self.values: dict[tuple[int, int], bytes] = {
            (0x1000, 0): bytes.fromhex("96010200"),
            (0x1001, 0): b"\x00",
            (0x1008, 0): TEXT,
            (0x1009, 0): b"",
            (0x1017, 0): b"\x00\x00",
            (0x2000, 0): b"",
        }
        self.read_only = {(0x1000, 0), (0x1008, 0)}
        self.writes: list[tuple[int, int, bytes]] = []

    def sdo_read(self, index: int, sub: int) -> bytes:
        if (index, sub) not in self.values:
            raise SdoAbort(NO_OBJECT)
        return self.values[(index, sub)]

    def sdo_write(self, index: int, sub: int, data: bytes) -> None:
        if (index, sub) not in self.values:
            raise SdoAbort(NO_OBJECT)
        if (index, sub) in self.read_only:
            raise SdoAbort(WRITE_RO)
        self.writes.append((index, sub, data))
        self.values[(index, sub)] = data


def frame(command: int, index: int = 0, sub: int = 0, payload: bytes = b"") -> bytes:
    """An 8-byte SDO request: command, index, sub, up to 4 data bytes."""
    return struct.pack("<BHB", command, index, sub) + payload.ljust(4, b"\x00")


def segment(command: int, data: bytes = b"") -> bytes:
    return bytes([command]) + data.ljust(7, b"\x00")


def abort_of(response: bytes | None) -> tuple[int, int, int]:
    """(index, sub, code) of an abort response; fails if it is not one."""
    assert response is not None, "expected an abort frame, got no response"
    assert response[0] == 0x80, f"expected an abort frame, got {response.hex(' ')}"
    return struct.unpack("<xHBI", response)
