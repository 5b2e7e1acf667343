"""The twin's LSS slave (CiA 305): LSS state, selective switch, configuration, inquiry, identification, fastscan.

Only the services the profile declares (capabilities.lss) answer; the others are ignored, as a device
without them would. The configured node-ID and bit timing go to ``config`` (``sim/engine/lss_configuration.py``:
pending until the node applies them, stored by store configuration); ``events`` tells the node when
something was configured and when the slave left the configuration state. Faults that break the slave
are the small classes at the bottom.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from encoder_conformance.cia.cia305 import (
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
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.lss_configuration import LssConfiguration
from encoder_conformance.sim.engine.nvm import NonVolatileMemory

Address = Callable[[], tuple[int, int, int, int]]  # 1018h sub 1..4 as the device holds them


class LssEvents(Protocol):
    """What the node hears from its LSS slave."""

    def configured(self, what: str) -> None:
        """A configure request succeeded: ``what`` is "node_id" or "bit_timing"."""

    def left_configuration(self) -> None:
        """Switched from the configuration state to the waiting state."""

    def activate_bit_timing(self, switch_delay_s: float) -> None:
        """Activate bit timing: silent for the delay, the pending bit rate, silent for the delay again."""


class _NoEvents:
    def configured(self, what: str) -> None:
        pass

    def left_configuration(self) -> None:
        pass

    def activate_bit_timing(self, switch_delay_s: float) -> None:
        pass


@dataclass
class LssSlave:
    """One node's LSS slave. ``answer`` sends one frame on 7E4h; ``node_id`` is the active node-ID;
    ``allowed`` says whether LSS frames are obeyed now (a device may take them only in some NMT states)."""

    services: frozenset[str]
    address: Address
    node_id: Callable[[], int]
    answer: Callable[[bytes], None]
    config: LssConfiguration = field(default_factory=lambda: LssConfiguration(NonVolatileMemory(None)))
    events: LssEvents = field(default_factory=_NoEvents)
    allowed: Callable[[], bool] = lambda: True
    can_store: bool = True
    bit_indices: frozenset[int] = frozenset(BIT_TIMING_TABLE_0)  # the table-0 indices the device accepts
    state: LssState = LssState.WAITING
    _selective: int = 0  # parts of the address matched so far, in order
    _identify: list[int] = field(default_factory=list)  # the identify-remote values received so far
    _scan_position: int | None = None  # fastscan LSSPos (None: not taking part)
    _by_command: dict[int, tuple[str, Callable[[bytes], None]]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self._by_command = self._handlers()

    @property
    def configured(self) -> bool:
        return self.node_id() != UNCONFIGURED_NODE_ID

    @property
    def pending_node_id(self) -> int | None:
        return self.config.pending_node_id

    @property
    def pending_bit_index(self) -> int | None:
        return self.config.pending_bit_index

    def on_frame(self, data: bytes) -> None:
        if len(data) < 8 or not self.allowed():
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
            LssCommand.ACTIVATE_BIT_TIMING: ("activate_bit_timing", self._activate_bit_timing),
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
            previous, self.state = self.state, LssState(data[1])
            if previous is LssState.CONFIGURATION and self.state is LssState.WAITING:
                self.events.left_configuration()

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
    def node_id_valid(self, node_id: int) -> bool:
        return 1 <= node_id <= MAX_NODE_ID or node_id == UNCONFIGURED_NODE_ID

    def bit_timing_valid(self, table: int, index: int) -> bool:
        return table == 0 and index in self.bit_indices

    def _configure_node_id(self, data: bytes) -> None:
        if self._configured(LssCommand.CONFIGURE_NODE_ID, self.node_id_valid(data[1])):
            self.config.configure_node_id(data[1])
            self.events.configured("node_id")

    def _activate_bit_timing(self, data: bytes) -> None:
        """Addressed to every slave, in any LSS state (CiA 305): the delay is bytes 1-2 in ms."""
        self.events.activate_bit_timing(struct.unpack_from("<H", data, 1)[0] / 1000)

    def _configure_bit_timing(self, data: bytes) -> None:
        if self._configured(LssCommand.CONFIGURE_BIT_TIMING, self.bit_timing_valid(data[1], data[2])):
            self.config.configure_bit_index(data[2])
            self.events.configured("bit_timing")

    def in_configuration(self) -> bool:
        return self.state is LssState.CONFIGURATION

    def _configured(self, command: int, valid: bool) -> bool:
        """Answer a configure request (configuration state only): error 0 when ``valid``, else 1 (out of range)."""
        if not self.in_configuration():
            return False
        self._send(command, bytes([ERROR_NONE if valid else ERROR_OUT_OF_RANGE]))
        return valid

    def _store_configuration(self, data: bytes) -> None:
        if not self.in_configuration():
            return
        stored = self.can_store and self.config.store(self.node_id())
        self._send(LssCommand.STORE_CONFIGURATION, bytes([ERROR_NONE if stored else ERROR_STORE_NOT_SUPPORTED]))

    # -- inquiry (configuration state only) --------------------------------------------------------
    def _inquire(self, data: bytes) -> None:
        if self.in_configuration():
            value = self.address()[INQUIRE_COMMANDS.index(data[0])]
            self._send(data[0], struct.pack("<I", value))

    def _inquire_node_id(self, data: bytes) -> None:
        if self.in_configuration():
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
        if self.identify_matches(*self._identify):
            self._send(LssCommand.IDENTIFY_SLAVE)

    def identify_matches(self, vendor: int, product: int, revision_low: int, revision_high: int,
                         serial_low: int, serial_high: int) -> bool:
        own = self.address()
        return (own[0] == vendor and own[1] == product and revision_low <= own[2] <= revision_high
                and serial_low <= own[3] <= serial_high)

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
        if not self.scan_matches(id_number, bit_checked, sub):
            return
        self._send(LssCommand.IDENTIFY_SLAVE)
        if bit_checked == 0:  # all 32 bits of this part matched: LSSPos becomes LSSNext
            if self.scan_complete(sub, next_sub):
                self._scan_position = None
                self.state = LssState.CONFIGURATION
            else:
                self._scan_position = next_sub & 3

    def scan_matches(self, id_number: int, bit_checked: int, sub: int) -> bool:
        """Bits 31..bit_checked of ``id_number`` equal this part of the address."""
        mask = (0xFFFFFFFF << bit_checked) & 0xFFFFFFFF
        return not (id_number ^ self.address()[sub]) & mask

    def scan_complete(self, sub: int, next_sub: int) -> bool:
        """The whole address matched: the serial number (LSSSub 3) confirmed and LSSNext back at the vendor-ID
        (CANopenNode PR#647: ``LSSNext < LSSSub`` alone lets a slave in before its serial number was checked)."""
        return sub == 3 and next_sub == 0


# -- faults ----------------------------------------------------------------------------------------------
@breaks(LssSlave, "lss_configure_not_answered")
class ConfigureNotAnswered(LssSlave):
    """Configure node-ID is carried out but never answered."""

    def _configure_node_id(self, data: bytes) -> None:
        if self.in_configuration() and self.node_id_valid(data[1]):
            self.config.configure_node_id(data[1])
            self.events.configured("node_id")


@breaks(LssSlave, "lss_node_id_range_unchecked")
class NodeIdRangeUnchecked(LssSlave):
    def node_id_valid(self, node_id: int) -> bool:
        return True


@breaks(LssSlave, "lss_bit_timing_unchecked")
class BitTimingUnchecked(LssSlave):
    def bit_timing_valid(self, table: int, index: int) -> bool:
        return True


@breaks(LssSlave, "lss_configuration_in_waiting")
class ConfigurationInWaiting(LssSlave):
    """Configure, store and inquire are answered in the waiting state too."""

    def in_configuration(self) -> bool:
        return True


@breaks(LssSlave, "lss_selective_ignores_serial")
class SelectiveIgnoresSerial(LssSlave):
    def _switch_selective(self, data: bytes) -> None:
        if data[0] == SELECTIVE_COMMANDS[-1]:
            data = data[:1] + struct.pack("<I", self.address()[3]) + data[5:]
        super()._switch_selective(data)


@breaks(LssSlave, "lss_inquire_wrong_serial")
class InquireWrongSerial(LssSlave):
    def _send(self, command: int, payload: bytes = b"") -> None:
        if command == LssCommand.INQUIRE_SERIAL:
            payload = struct.pack("<I", (struct.unpack_from("<I", payload)[0] + 1) & 0xFFFFFFFF)
        super()._send(command, payload)


@breaks(LssSlave, "lss_identify_answered_when_configured")
class IdentifyAnsweredWhenConfigured(LssSlave):
    def _identify_non_configured(self, data: bytes) -> None:
        self._send(LssCommand.IDENTIFY_NON_CONFIGURED_SLAVE)


@breaks(LssSlave, "lss_identify_ignores_ranges")
class IdentifyIgnoresRanges(LssSlave):
    """Identify remote slave is answered whatever the revision and serial ranges."""

    def identify_matches(self, vendor: int, product: int, *ranges: int) -> bool:
        return (vendor, product) == self.address()[:2]


@breaks(LssSlave, "lss_fastscan_ignores_checked_bit")
class FastscanIgnoresCheckedBit(LssSlave):
    """Fastscan steps compare one bit too few: the bit being checked is ignored."""

    def scan_matches(self, id_number: int, bit_checked: int, sub: int) -> bool:
        mask = (0xFFFFFFFF << (bit_checked + 1)) & 0xFFFFFFFF
        return not (id_number ^ self.address()[sub]) & mask


@breaks(LssSlave, "lss_fastscan_completes_early")
class FastscanCompletesEarly(LssSlave):
    """The completion condition is too broad (CANopenNode PR#647): a slave enters the configuration state
    whenever LSSNext is lower than LSSSub, before its serial number was checked."""

    def scan_complete(self, sub: int, next_sub: int) -> bool:
        return next_sub < sub


@breaks(LssSlave, "lss_fastscan_reset_ignored")
class FastscanResetIgnored(LssSlave):
    """BitChecked 80h is answered but does not restart a scan in progress."""

    def _fastscan(self, data: bytes) -> None:
        position = self._scan_position
        super()._fastscan(data)
        if data[5] == FASTSCAN_RESET_BIT and position is not None:
            self._scan_position = position


@breaks(LssSlave, "lss_bit_timing_refused")
class BitTimingRefused(LssSlave):
    def bit_timing_valid(self, table: int, index: int) -> bool:
        return False


@breaks(LssSlave, "lss_activate_ignored")
class ActivateIgnored(LssSlave):
    """Activate bit timing does nothing: no silence, no switch to the configured bit rate."""

    def _activate_bit_timing(self, data: bytes) -> None:
        pass


@breaks(LssSlave, "lss_activate_only_in_configuration")
class ActivateOnlyInConfiguration(LssSlave):
    """A variant, not a fault: activate bit timing is obeyed only in the configuration state (CANopenNode)."""

    def _activate_bit_timing(self, data: bytes) -> None:
        if self.in_configuration():
            super()._activate_bit_timing(data)


@breaks(LssSlave, "lss_node_id_ffh_refused")
class NodeIdFfhRefused(LssSlave):
    """A variant, not a fault: configure node-ID takes 1..127 only; FFh (unconfigured) is refused with error 1."""

    def node_id_valid(self, node_id: int) -> bool:
        return 1 <= node_id <= MAX_NODE_ID


@breaks(LssSlave, "lss_bit_timing_auto_and_100k")
class BitTimingAutoAnd100k(LssSlave):
    """A variant, not a fault: table-0 index 9 (automatic detection) and 5 (100 kbit/s in older LSS tables) are accepted
    whatever the profile lists."""

    def bit_timing_valid(self, table: int, index: int) -> bool:
        return super().bit_timing_valid(table, index) or (table == 0 and index in (5, 9))


@breaks(LssSlave, "lss_inquire_late_in_waiting")
class InquireLateInWaiting(LssSlave):
    """Inquire node-ID in the waiting state is answered late: just before the slave takes the master's next LSS
    frame, which the tester sends only once its window for that answer has ended (only the late-frame ledger sees
    it, whatever the pace of the run)."""

    _withheld: bytes | None = None

    def on_frame(self, data: bytes) -> None:
        if self._withheld is not None:
            withheld, self._withheld = self._withheld, None
            self.answer(withheld)
        super().on_frame(data)

    def _inquire_node_id(self, data: bytes) -> None:
        if self.in_configuration():
            super()._inquire_node_id(data)
            return
        self._withheld = bytes([LssCommand.INQUIRE_NODE_ID, self.node_id()]).ljust(8, b"\x00")
