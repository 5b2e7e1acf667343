"""What CiA 301 says a node does on each NMT command: the state it enters, which values a reset brings
back, and which traffic each state allows. Pure (no I/O): the state-machine suite drives a device and
this model side by side and compares them after every step.

- §7.3.2.2 (state diagram): start -> operational, stop -> stopped, enter pre-operational ->
  pre-operational; reset node / reset communication -> initialisation, boot-up (00h), then
  pre-operational, or operational where a documented autostart object says so (quirk
  ``nmt_autostart_object``, read from its stored value).
- §7.3.2.2.3 (initialisation): reset communication loads the communication area 1000h-1FFFh, reset node
  also the application area, from what the device has stored (its factory values where nothing is).
  A plain state change loads nothing. Bits a documented quirk forces at an init event (``bits_forced_at_init``)
  are set on top.
- §7.3.2.2.4 (services per state): SDO in pre-operational and operational, PDO in operational only,
  NMT and error control (heartbeat: 04h stopped, 05h operational, 7Fh pre-operational) in all.
- §7.2.8.3.1: a command is obeyed when its node-ID is the node's own or 0 (all nodes).
- A write of a PDO's communication or mapping parameter (1400h-1BFFh) outside pre-operational may be refused with
  08000022h (§7.2.4.3.17 table 22, "present device state"; open reading pdo-config-refused-in-operational: the WDGA
  manual restricts PDO parameterisation to pre-operational, M §8.5.1): the value then stays.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from encoder_conformance.cia.cia301 import (
    COMMUNICATION_AREA,
    NMT_COMMAND_TARGET,
    RPDO_COMMUNICATION,
    RPDO_MAPPING,
    TPDO_COMMUNICATION,
    TPDO_MAPPING,
    NmtCommand,
    NmtState,
    SdoAbortCode,
)

__all__ = ["NmtModel", "Tracked"]

#: where the state-changing commands lead (§7.3.2.2)
COMMAND_TARGET = NMT_COMMAND_TARGET
#: the init event of each reset, as quirk ``bits_forced_at_init`` names it
RESET_EVENT = {NmtCommand.RESET_NODE: "nmt_81h", NmtCommand.RESET_COMMUNICATION: "nmt_82h"}
HEARTBEAT_TIME = (0x1017, 0)
PDO_PARAMETERS = (RPDO_COMMUNICATION, RPDO_MAPPING, TPDO_COMMUNICATION, TPDO_MAPPING)


@dataclass
class Tracked:
    """One value the model follows: what the device has stored (read before any write) and holds now."""

    index: int
    sub: int
    size: int
    stored: int
    current: int
    forced_bits: int = 0  # set at the init events in ``forced_at`` (documented quirk)
    forced_at: frozenset[str] = frozenset()
    preop_only: bool = False  # writes refused outside pre-operational (documented quirk)
    auto_stored: bool = False  # the device stores every write itself (persisted_by auto)

    @property
    def label(self) -> str:
        return f"{self.index:04X}h.{self.sub:02X}"

    @property
    def communication(self) -> bool:
        return self.index in COMMUNICATION_AREA

    def reload(self, event: str) -> None:
        self.current = self.stored | (self.forced_bits if event in self.forced_at else 0)


@dataclass
class NmtModel:
    """The NMT state and the followed values of one node."""

    node_id: int
    boot_state: NmtState = NmtState.PRE_OPERATIONAL  # where a reset ends (autostart: operational)
    state: NmtState = NmtState.PRE_OPERATIONAL
    values: dict[tuple[int, int], Tracked] = field(default_factory=dict)

    def track(self, value: Tracked) -> None:
        self.values[(value.index, value.sub)] = value

    # -- commands ------------------------------------------------------------------------
    def addressed(self, target: int) -> bool:
        return target in (0, self.node_id)

    def command(self, command: NmtCommand, target: int) -> bool:
        """Apply an NMT command; True when it resets the node (a boot-up is owed)."""
        if not self.addressed(target):
            return False
        if command in COMMAND_TARGET:
            self.state = COMMAND_TARGET[command]
            return False
        whole = command is NmtCommand.RESET_NODE
        for value in self.values.values():
            if whole or value.communication:
                value.reload(RESET_EVENT[command])
        self.state = self.boot_state
        return True

    # -- services ------------------------------------------------------------------------
    @property
    def sdo_answered(self) -> bool:
        return self.state in (NmtState.PRE_OPERATIONAL, NmtState.OPERATIONAL)

    @property
    def pdo_allowed(self) -> bool:
        return self.state is NmtState.OPERATIONAL

    @property
    def heartbeat_byte(self) -> int:
        return int(self.state)

    @property
    def heartbeat_ms(self) -> int:
        """The producer heartbeat time in force (0: no heartbeat, also where 1017h is not followed)."""
        value = self.values.get(HEARTBEAT_TIME)
        return value.current if value is not None else 0

    def may_write(self, key: tuple[int, int]) -> bool:
        """An SDO write of ``key`` is answered and accepted in the present state."""
        return self.sdo_answered and (not self.values[key].preop_only or self.state is NmtState.PRE_OPERATIONAL)

    def refusal_allowed(self, key: tuple[int, int], code: int) -> bool:
        """A refused write of ``key`` with abort ``code`` is a reading CiA 301 allows: a PDO parameter refused with
        08000022h (present device state) outside pre-operational."""
        pdo = any(key[0] in area for area in PDO_PARAMETERS)
        return pdo and code == SdoAbortCode.WRONG_STATE and self.state is not NmtState.PRE_OPERATIONAL

    def write(self, key: tuple[int, int], value: int) -> None:
        tracked = self.values[key]
        tracked.current = value
        if tracked.auto_stored:
            tracked.stored = value

    def expected(self, key: tuple[int, int]) -> int:
        return self.values[key].current
