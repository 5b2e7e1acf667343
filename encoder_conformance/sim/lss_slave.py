"""The twin's LSS slave (CiA 305): LSS state, selective switch, configuration, inquiry, identification, fastscan.

Only the services the profile declares (capabilities.lss) answer; the others are ignored, as a device
without them would. The configured node-ID and bit timing are pending until the node applies them
(``pending_node_id``/``pending_bit_index``); store configuration hands them to ``store``.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass, field

from ..cia305 import (
    BIT_TIMING_TABLE_0,
    ERROR_NONE,
    ERROR_OUT_OF_RANGE,
    ERROR_STORE_NOT_SUPPORTED,
    FASTSCAN_RESET_BIT,
    IDENTIFY_RANGE_COMMANDS,
    INQUIRE_COMMANDS,
    MAX_NODE_ID,
    SELECTIVE_COMMANDS,
    UNCONFIGURED_NODE_ID,
    LssCommand,
    LssState,
)

Address = Callable[[], tuple[int, int, int, int]]  # 1018h sub 1..4 as the device holds them


@dataclass
class LssSlave:
    """One node's LSS slave. ``answer`` sends one frame on 7E4h; ``node_id`` is the active node-ID."""

    services: frozenset[str]
    address: Address
    node_id: Callable[[], int]
    answer: Callable[[bytes], None]
    store: Callable[[int | None, int | None], bool] | None = None  # (node-ID, bit index) -> stored
    state: LssState = LssState.WAITING
    pending_node_id: int | None = None
    pending_bit_index: int | None = None
    _selective: int = 0  # parts of the address matched so far, in order
    _identify: list[int] = field(default_factory=list)  # the identify-remote values received so far
    _scan_position: int | None = None  # fastscan LSSPos (None: not taking part)
    _by_command: dict[int, tuple[str, Callable[[bytes], None]]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self._by_command = self._handlers()

    @property
    def configured(self) -> bool:
        return self.node_id() != UNCONFIGURED_NODE_ID

    def on_frame(self, data: bytes) -> None:
        if len(data) < 8:
            return  # CiA 305 frames are 8 bytes; a shorter one is not an LSS request
        command = data[0]
        handler = self._by_command.get(command)
        if handler is not None:
            service, method = handler
            if service in self.services:
                method(data)

    def _handlers(self) -> dict[int, tuple[str, Callable[[bytes], None]]]:
        handlers: dict[int, tuple[str, Callable[[bytes], None]]] = {
            LssCommand.SWITCH_STATE_GLOBAL: ("switch_global", self._switch_global),
            LssCommand.CONFIGURE_NODE_ID: ("configure_node_id", self._configure_node_id),
            LssCommand.CONFIGURE_BIT_TIMING: ("configure_bit_timing", self._configure_bit_timing),
            LssCommand.ACTIVATE_BIT_TIMING: ("activate_bit_timing", lambda data: None),
            LssCommand.STORE_CONFIGURATION: ("store_configuration", self._store_configuration),
            LssCommand.INQUIRE_NODE_ID: ("inquire_node_id", self._inquire_node_id),
            LssCommand.IDENTIFY_NON_CONFIGURED: ("identify_non_configured", self._identify_non_configured),
            LssCommand.FASTSCAN: ("fastscan", self._fastscan),
        }
        handlers.update({cs: ("switch_selective", self._switch_selective) for cs in SELECTIVE_COMMANDS})
        handlers.update({cs: ("inquire_identity", self._inquire) for cs in INQUIRE_COMMANDS})
        handlers.update({cs: ("identify_remote_slave", self._identify_remote) for cs in IDENTIFY_RANGE_COMMANDS})
        return handlers

    def _send(self, command: int, payload: bytes = b"") -> None:
        self.answer(bytes([command]) + payload.ljust(7, b"\x00")[:7])

    # -- state ---------------------------------------------------------------------------------
    def _switch_global(self, data: bytes) -> None:
        if data[1] in (LssState.WAITING, LssState.CONFIGURATION):
            self.state = LssState(data[1])

    def _switch_selective(self, data: bytes) -> None:
        part = SELECTIVE_COMMANDS.index(data[0])
        value = struct.unpack_from("<I", data, 1)[0]
        if part != self._selective or value != self.address()[part]:
            self._selective = 1 if part == 0 and value == self.address()[0] else 0
            return
        self._selective += 1
        if self._selective == 4:
            self._selective = 0
            self.state = LssState.CONFIGURATION
            self._send(LssCommand.SWITCH_SELECTIVE_RESPONSE)

    # -- configuration (configuration state only) --------------------------------------------------
    def _configure_node_id(self, data: bytes) -> None:
        node_id = data[1]
        valid = 1 <= node_id <= MAX_NODE_ID or node_id == UNCONFIGURED_NODE_ID
        if self._configured(LssCommand.CONFIGURE_NODE_ID, valid):
            self.pending_node_id = node_id

    def _configure_bit_timing(self, data: bytes) -> None:
        table, index = data[1], data[2]
        if self._configured(LssCommand.CONFIGURE_BIT_TIMING, table == 0 and index in BIT_TIMING_TABLE_0):
            self.pending_bit_index = index

    def _configured(self, command: int, valid: bool) -> bool:
        """Answer a configure request (configuration state only): error 0 when ``valid``, else 1 (out of range)."""
        if self.state is not LssState.CONFIGURATION:
            return False
        self._send(command, bytes([ERROR_NONE if valid else ERROR_OUT_OF_RANGE]))
        return valid

    def _store_configuration(self, data: bytes) -> None:
        if self.state is not LssState.CONFIGURATION:
            return
        stored = self.store is not None and self.store(self.pending_node_id, self.pending_bit_index)
        self._send(LssCommand.STORE_CONFIGURATION, bytes([ERROR_NONE if stored else ERROR_STORE_NOT_SUPPORTED]))

    # -- inquiry (configuration state only) --------------------------------------------------------
    def _inquire(self, data: bytes) -> None:
        if self.state is LssState.CONFIGURATION:
            value = self.address()[INQUIRE_COMMANDS.index(data[0])]
            self._send(data[0], struct.pack("<I", value))

    def _inquire_node_id(self, data: bytes) -> None:
        if self.state is LssState.CONFIGURATION:
            self._send(LssCommand.INQUIRE_NODE_ID, bytes([self.node_id()]))

    # -- identification ------------------------------------------------------------------------------
    def _identify_remote(self, data: bytes) -> None:
        step = IDENTIFY_RANGE_COMMANDS.index(data[0])
        value = struct.unpack_from("<I", data, 1)[0]
        if step == 0:
            self._identify = []
        if step != len(self._identify):
            self._identify = []
            return
        self._identify.append(value)
        if step < 5:
            return
        vendor, product, revision_low, revision_high, serial_low, serial_high = self._identify
        own = self.address()
        if (own[0] == vendor and own[1] == product and revision_low <= own[2] <= revision_high
                and serial_low <= own[3] <= serial_high):
            self._send(LssCommand.IDENTIFY_SLAVE)

    def _identify_non_configured(self, data: bytes) -> None:
        if not self.configured:
            self._send(LssCommand.IDENTIFY_NON_CONFIGURED_SLAVE)

    def _fastscan(self, data: bytes) -> None:
        """CiA 305 fastscan: only non-configured slaves in waiting state take part."""
        if self.configured or self.state is not LssState.WAITING:
            return
        id_number, bit_checked, sub, next_sub = struct.unpack_from("<IBBB", data, 1)
        if bit_checked == FASTSCAN_RESET_BIT:
            self._scan_position = 0
            self._send(LssCommand.IDENTIFY_SLAVE)
            return
        if self._scan_position != sub or bit_checked > 31 or sub > 3:
            return
        mask = (0xFFFFFFFF << bit_checked) & 0xFFFFFFFF
        if (id_number ^ self.address()[sub]) & mask:
            return
        self._send(LssCommand.IDENTIFY_SLAVE)
        if bit_checked == 0:  # all 32 bits matched: LSSPos becomes LSSNext; wrapping back means found
            if next_sub < sub:
                self._scan_position = None
                self.state = LssState.CONFIGURATION
            else:
                self._scan_position = next_sub
