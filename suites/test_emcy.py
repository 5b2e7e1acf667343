"""EMCY producer: frame layout, COB-ID from 1014h, error register and error history (CiA 301 §7.2.7)."""

from __future__ import annotations

import pytest

from encoder_conformance.dut.frames import format_frames

pytestmark = [pytest.mark.spec("CiA 301 §7.2.7 (EMCY)"), pytest.mark.requires("emcy")]

ERROR_CODE = 0x5000  # device hardware (CiA 301 table 21)


def test_emcy_frame_on_error(dut, error_stimulus, nmt_reset_after):
    """An internal error produces one 8-byte EMCY on the 1014h COB-ID with code and error register."""
    cob_id = dut.read_uint(0x1014) & 0x7FF if dut.profile.entry(0x1014, 0) else 0x80 + dut.node_id
    mark = dut.frames.mark()
    error_stimulus.raise_emcy(ERROR_CODE, 0x01)
    frame = dut.frames.wait_for(lambda m: m.is_rx and 0x81 <= m.arbitration_id <= 0xFF, 0.5, mark)
    assert frame is not None, f"no EMCY within 500 ms\n{format_frames(dut.frames.since(mark))}"
    assert frame.arbitration_id == cob_id, f"EMCY on {frame.arbitration_id:03X}h, 1014h says {cob_id:03X}h"
    assert frame.dlc == 8, f"EMCY has DLC {frame.dlc}, CiA 301 requires 8"
    code = int.from_bytes(frame.data[0:2], "little")
    assert code == ERROR_CODE, f"EMCY error code {code:04X}h, expected {ERROR_CODE:04X}h"
    register = dut.read_uint(0x1001)
    assert frame.data[2] == register, f"EMCY byte 2 = {frame.data[2]:02X}h but 1001h = {register:02X}h"
