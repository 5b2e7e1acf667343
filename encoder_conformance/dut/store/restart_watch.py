"""Whether a node shows what it stored: it restarted and nobody has written to it since.

After a power-on, an NMT reset node or a store command that reboots the device (FRABA POSITAL),
a device loads every parameter from its memory; until something writes to it, reading it reads
what it stored. The custody uses this to skip a reset (4 s on a POSITAL) that would only reload
the same values. A reset-communication boot-up reloads only 1000h-1FFFh, so it does not count.
"""

from __future__ import annotations

import threading

import can

from encoder_conformance.cia.cia301 import HEARTBEAT_BASE, SDO_REQUEST_BASE, NmtCommand, SdoClientCommand

_DOWNLOADS = {SdoClientCommand.INITIATE_DOWNLOAD, SdoClientCommand.BLOCK_DOWNLOAD}  # what starts a download


class RestartWatch(can.Listener):
    """Follows every frame to and from one node (any sender: a PLC on a bench writes too)."""

    def __init__(self, node_id: int) -> None:
        self._node_id = node_id
        self._lock = threading.Lock()
        self._shows_stored = False
        self._communication_reset = False

    @property
    def shows_stored(self) -> bool:
        """True while the node's values are the ones it loaded from its memory at its last restart."""
        with self._lock:
            return self._shows_stored

    def on_message_received(self, msg: can.Message) -> None:
        if msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
            return
        data = bytes(msg.data)
        node = self._node_id
        with self._lock:
            if msg.arbitration_id == SDO_REQUEST_BASE + node and data and data[0] >> 5 in _DOWNLOADS:
                self._shows_stored = False
            elif msg.arbitration_id == 0 and len(data) == 2 and data[1] in (0, node):
                if data[0] == NmtCommand.RESET_COMMUNICATION:
                    self._communication_reset = True
                elif data[0] == NmtCommand.RESET_NODE:
                    self._communication_reset = False
            elif msg.arbitration_id == HEARTBEAT_BASE + node and data == b"\x00":
                self._shows_stored = not self._communication_reset
                self._communication_reset = False
