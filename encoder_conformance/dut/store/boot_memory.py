"""What a device says at boot about its stored parameters, and whether a run changed that.

CANopenNode's demo device started without its storage files finds no valid stored data at every start-up and says
so after the boot-up: EMCY 5000h (device hardware, CiA 301 v4.2.0 §7.2.7.1 table 21) with 1001h bit 0. A store
command (1010h) writes the files: it then boots without the error, and, no error holding it, into another NMT
state. No write takes that back, and 1011h restore defaults does not either: CANopenNode's CO_storageLinux.c
writes a file that means "use the defaults", which loads without an error too. The custody records the EMCY codes
after the snapshot's boot-up and after its last boot-up of the give-back, and says so where they differ.
"""

from __future__ import annotations

import can

from encoder_conformance.cia.cia301 import EMCY_BASE, EmcyCode
from encoder_conformance.dut.link.device import DeviceLink

#: frames looked at back from now for the last boot-up (a give-back reads and writes every value: ~1,000 frames)
LOOK_BACK = 5000


def errors_after_boot(dut: DeviceLink) -> list[int]:
    """The EMCY error codes the node sent after its latest boot-up in the frame log (none: [])."""
    emcy = EMCY_BASE + dut.node_id

    def wanted(msg: can.Message) -> bool:
        return dut.is_heartbeat(msg) or (msg.is_rx and msg.arbitration_id == emcy and len(msg.data) >= 2)

    frames = [m for m in dut.frames.last(LOOK_BACK) if wanted(m)]  # a copy of the log's end: no indexing into it
    boots = [i for i, m in enumerate(frames) if dut.is_heartbeat(m) and bytes(m.data) == b"\x00"]
    after = frames[boots[-1] + 1:] if boots else frames
    return [code for m in after if not dut.is_heartbeat(m) and (code := int.from_bytes(m.data[:2], "little"))]


def memory_note(found: list[int], now: list[int], stores: int) -> str | None:
    """Why the device's memory is not as found (None: nothing shows it): it reported no valid stored data at the
    start (EMCY 5000h after its boot-up), the run sent ``stores`` store commands, and it boots without it now."""
    if EmcyCode.DEVICE_HARDWARE not in found or EmcyCode.DEVICE_HARDWARE in now or not stores:
        return None
    return ("the device reported no valid stored parameters when the run began (EMCY 5000h after its boot-up, CiA 301 "
            f"§7.2.7.1) and boots without it now: the {stores} store command(s) of the run left a full set of stored "
            "parameters, so it starts without that error and may enter another NMT state. No write or restore "
            "defaults (1011h) takes that back; CANopenNode's demo: stop it and delete the storage files it was "
            "started with (CO_storageLinux.c: a missing file is this error, 1011h writes a file of defaults)")
