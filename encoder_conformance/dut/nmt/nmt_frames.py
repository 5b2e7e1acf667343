"""What an NMT command frame is and the state a command leads to, for those who only read the bus (the late-frame
ledger, ``dut/link/late_frames.py``); sending one is ``commands.py``'s. Imports nothing of ``dut/``."""

from __future__ import annotations

import can

from encoder_conformance.cia.cia301 import NMT_COB_ID, NMT_COMMAND_NAMES, NMT_COMMAND_TARGET


def is_command(msg: can.Message) -> bool:
    """An NMT command on the bus (any master's)."""
    return msg.arbitration_id == NMT_COB_ID and not msg.is_remote_frame


def target_state(command: str) -> int:
    """The heartbeat state byte the NMT ``command`` (a name of ``NMT_COMMAND_NAMES``: start, stop, ...) leads to."""
    return int(NMT_COMMAND_TARGET[NMT_COMMAND_NAMES[command]])
