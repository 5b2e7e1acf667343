"""Count the commands a run sends that change what the device remembers (EEPROM/flash wear).

Watches the tester's own frames (FrameLog listener), so every path counts: canopen's client, raw
SDO frames, fixtures, the restore. A download to 1010h/1011h, to a manufacturer store object, or
to an entry the device stores by itself (``persisted_by: auto``) may change the stored
configuration: the restore then checks and puts back what is stored. So do LSS store configuration
(17h) and, on a device that stores them by itself, LSS configure node-ID / bit timing.
"""

from __future__ import annotations

import threading
from collections import Counter

import can

from encoder_conformance.cia.cia301 import (
    RESTORE_DEFAULT_PARAMETERS,
    SDO_REQUEST_BASE,
    STORE_PARAMETERS,
    SdoClientCommand,
)
from encoder_conformance.cia.cia305 import MASTER_COB_ID as LSS_MASTER_COB_ID
from encoder_conformance.cia.cia305 import LssCommand
from encoder_conformance.profile.quirk_effects import (
    LssConfigAutoStored,
    ManufacturerStoreObject,
    StoreRebootsWithoutReply,
)
from encoder_conformance.profile.schema import DeviceProfile

#: SDO client command specifiers that start a download (CiA 301 §7.2.4.3): initiate, block initiate
_DOWNLOAD_INITIATE = {SdoClientCommand.INITIATE_DOWNLOAD, SdoClientCommand.BLOCK_DOWNLOAD}
#: how the counts name writes to entries the device stores by itself
AUTO_STORED = "writes the device stores by itself"


def store_command_objects(profile: DeviceProfile) -> frozenset[int]:
    """Indices whose writes are commands that store or restore (1010h, 1011h, manufacturer ones)."""
    indices = {STORE_PARAMETERS, RESTORE_DEFAULT_PARAMETERS}
    for effect in (ManufacturerStoreObject, StoreRebootsWithoutReply):
        params = profile.params_of(effect)
        if params is not None:
            indices.add(params.index)
    return frozenset(indices)


class StoreWatch(can.Listener):
    """Counts store/restore commands and self-storing writes the tester sends to one node."""

    def __init__(self, profile: DeviceProfile, node_id: int) -> None:
        self._request_id = SDO_REQUEST_BASE + node_id
        self._commands = store_command_objects(profile)
        self._auto = frozenset((i, s) for i, s, _, e in profile.iter_entries() if e.persisted_by == "auto")
        self._lss_stores = _lss_stores(profile)
        self._lock = threading.Lock()
        self.counts: Counter[str] = Counter()
        self.by_restore: Counter[str] = Counter()
        self.restoring = False

    def on_message_received(self, msg: can.Message) -> None:
        if not msg.is_rx and msg.arbitration_id == LSS_MASTER_COB_ID and msg.data and msg.data[0] in self._lss_stores:
            self._count(self._lss_stores[msg.data[0]])
            return
        if msg.is_rx or msg.arbitration_id != self._request_id or len(msg.data) < 4:
            return
        if msg.data[0] >> 5 not in _DOWNLOAD_INITIATE:
            return
        index, sub = msg.data[1] | msg.data[2] << 8, msg.data[3]
        if index == RESTORE_DEFAULT_PARAMETERS:
            kind = f"restore defaults {index:04X}h.{sub:02X}"
        elif index in self._commands:
            kind = f"store {index:04X}h.{sub:02X}"
        elif (index, sub) in self._auto:
            kind = AUTO_STORED
        else:
            return
        self._count(kind)

    def _count(self, kind: str) -> None:
        with self._lock:
            (self.by_restore if self.restoring else self.counts)[kind] += 1

    @property
    def total(self) -> int:
        """Commands the tests sent (not the restore's own)."""
        with self._lock:
            return sum(self.counts.values())

    @property
    def total_by_restore(self) -> int:
        with self._lock:
            return sum(self.by_restore.values())


def _lss_stores(profile: DeviceProfile) -> dict[int, str]:
    """LSS command specifiers that store on this device -> how the report names them."""
    stores = {int(LssCommand.STORE_CONFIGURATION): "LSS store configuration"}
    auto = profile.params_of(LssConfigAutoStored)
    if auto is not None:
        if "node_id" in auto.auto_stored:
            stores[int(LssCommand.CONFIGURE_NODE_ID)] = "LSS configure node-ID (stored by the device itself)"
        if "bit_timing" in auto.auto_stored:
            stores[int(LssCommand.CONFIGURE_BIT_TIMING)] = "LSS configure bit timing (stored by the device itself)"
    return stores
