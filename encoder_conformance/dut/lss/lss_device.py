"""The device under test seen through LSS (CiA 305 v3.0.0): its LSS address, node-ID and bit rate as found,
the services its profile declares, the waits a test owes it, and the put-back after a test.

A test may move the device to another node-ID or make it unconfigured (255); it says so first (``moving_to``,
which the run's snapshot records, so that ``restore --from`` looks there too). ``put_back`` finds the device
wherever the test left it and brings it back (``dut/lss/lss_custody.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import can

from encoder_conformance.cia.cia301 import HEARTBEAT_BASE, SDO_REQUEST_BASE, SDO_RESPONSE_BASE
from encoder_conformance.cia.cia305 import (
    BIT_TIMING_TABLE_0,
    FASTSCAN_RESET_BIT,
    MASTER_COB_ID,
    UNCONFIGURED_NODE_ID,
    LssCommand,
    LssState,
)
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.lss.lss_custody import Changes, LssCustody, failure
from encoder_conformance.dut.lss.lss_master import LssAddress, LssAnswer, LssMaster
from encoder_conformance.dut.nmt.commands import send_command
from encoder_conformance.dut.nmt.heartbeat_state import describe
from encoder_conformance.dut.sdo.sdo_frames import upload_request
from encoder_conformance.profile import quirk_effects as fx

#: the LSS states ``LssDevice.transition`` reaches (CiA 305 v3.0.0 §4.2, the LSS FSA)
LSS_STATES = ("waiting", "configuration")


def table_index(bitrate: int, table: dict[int, int] = BIT_TIMING_TABLE_0) -> int | None:
    """LSS table-0 index of a bit rate (None: not in the table)."""
    return next((index for index, rate in table.items() if rate == bitrate), None)


@dataclass
class LssDevice:
    """LSS view of the device under test."""

    dut: DeviceLink
    master: LssMaster
    address: LssAddress
    bit_index: int | None  # the table-0 index of the bit rate in use, where known
    power_cycle: Callable[[], Mark] | None = None  # the bench switch's cycle, where there is one: the power-on mark
    moved_to: set[int] = field(default_factory=set)  # node-IDs a test gave the device
    made_unconfigured: bool = False
    start: Mark = field(init=False)  # before the test's first LSS frame (set at construction)
    unconfigured_since: Mark | None = None  # at the reset or power-on that made it unconfigured
    on_move: Callable[[int], None] | None = None  # told each node-ID before a test gives it (the run's snapshot)
    on_settled: Callable[[], None] | None = None  # told when the device is back where it was found
    restore_hint: str = ""  # the command that finishes a put-back later (``restore --from``)

    def __post_init__(self) -> None:
        self.start = self.dut.frames.mark()

    @property
    def services(self) -> frozenset[str]:
        return frozenset(self.dut.profile.capabilities.lss)

    @property
    def node_id(self) -> int:
        """The node-ID the device was found at (the DUT's)."""
        return self.dut.node_id

    @property
    def applies_on_reset(self) -> bool:
        """CiA 305 v3: a configured node-ID becomes active on NMT reset communication; the legacy quirk
        ``lss_only_in_states`` with ``activation: power_cycle``: only at power-on, from what was stored."""
        quirk = self.dut.profile.params_of(fx.LssOnlyInStates)
        return quirk is None or quirk.activation == "reset_communication"

    @property
    def auto_stored(self) -> frozenset[str]:
        quirk = self.dut.profile.params_of(fx.LssConfigAutoStored)
        return frozenset(() if quirk is None else quirk.auto_stored)

    # -- selecting the device ----------------------------------------------------------------------
    def select(self) -> bool:
        """Into the configuration state: by its LSS address where the device has switch selective
        (other LSS devices on the bus stay out), else by switch global."""
        if "switch_selective" in self.services:
            return self.master.switch_selective(self.address)
        self.master.switch_global(LssState.CONFIGURATION)
        return True

    def _state_seen(self) -> int | None:
        """The NMT state the newest heartbeat at the device's node-ID since the test began reports (LSS may be
        documented only in some states: quirk lss_only_in_states)."""
        beats = self.dut.frames.since(self.start, lambda m: _from(m, HEARTBEAT_BASE + self.node_id)
                                      and bool(m.data) and m.data[0] != 0)
        return beats[-1].data[0] if beats else None

    def into_lss_state(self, node_id: int) -> None:
        """Quirk lss_only_in_states without operational: NMT enter pre-operational at ``node_id`` and an SDO answer
        there, as the manual's procedure stops the device first (WDGA M §8.2.4); a device that started itself after
        a power cycle would ignore LSS. Nothing where LSS is obeyed in every NMT state (CiA 305)."""
        quirk = self.dut.profile.params_of(fx.LssOnlyInStates)
        if quirk is None or "operational" in quirk.states:
            return
        send_command(self.dut, "pre-operational", node_id=node_id)
        assert self.answers_at(node_id), f"no SDO answer at node-ID {node_id} after NMT enter pre-operational"

    def leave(self) -> Mark:
        """Switch state global 0: back to the waiting state (nothing answers it); the mark before it."""
        return self.master.switch_global(LssState.WAITING)

    def transition(self, state: str) -> None:
        """The device into the LSS ``state`` by one call, as ``dut.nmt.transition`` reaches an NMT state, and seen
        there by what the state answers: "configuration" by switch state selective to its LSS address where it has
        that service (its 44h answer), else by switch state global and an inquire node-ID answered (where the device
        has that service; without it the test's next service shows the state); "waiting" by switch state global 0
        (which nothing answers). AssertionError naming the NMT state the heartbeat reports where the device did not
        get there."""
        if state not in LSS_STATES:
            raise ValueError(f"unknown LSS state {state!r}: one of {', '.join(LSS_STATES)}")
        if state == "waiting":
            self.leave()
            return
        if "switch_selective" in self.services:
            how, there = f"switch state selective to {self.address.describe()}: no answer (44h)", self.select()
        else:
            how, there = "switch state global: inquire node-ID unanswered after it", self.select()
            if "inquire_node_id" in self.services:
                there = self.master.inquire_node_id() is not None
        assert there, f"{how}; the heartbeat at node-ID {self.node_id} reports {describe(self._state_seen())}"

    def sent_after_request(self, mark: Mark, window: float) -> list[can.Message]:
        """The node's frames within ``window`` after the LSS request at ``mark``, less those that crossed it:
        within the master's silence window (the profile's LSS response window plus the tester's margin) one
        frame per COB-ID may already have been on its way when the request arrived (in the device's transmit
        buffer, or sent by a twin's thread that looked just before). A device that goes on sending shows a
        second frame of that COB-ID, or frames after the silence window."""
        crossing_s = min(window, self.master.silence_s)
        early = self.dut.frames_from_node(mark, crossing_s)
        later = self.dut.frames_from_node(self.dut.frames.mark(), window - crossing_s)
        seen: set[int] = set()
        repeated = []
        for msg in early:
            if msg.arbitration_id in seen:
                repeated.append(msg)
            seen.add(msg.arbitration_id)
        return repeated + later

    # -- a node-ID other than the DUT's ------------------------------------------------------------
    def free_node_id(self) -> int:
        """A node-ID nobody answers SDO at (the next ones after the device's)."""
        for step in range(1, 127):
            candidate = (self.node_id - 1 + step) % 127 + 1
            if not self.answers_at(candidate, timeout=self.dut.sdo_silence_s):
                return candidate
        raise AssertionError("every node-ID 1..127 answers SDO: no free node-ID to move the device to")

    def answers_at(self, node_id: int, timeout: float | None = None) -> bool:
        """Does a node answer an SDO read of 1000h at ``node_id``?"""
        mark = self.dut.frames.mark()
        self.dut.network.send_message(SDO_REQUEST_BASE + node_id, upload_request(0x1000, 0))
        wait = self.dut.sdo_timeout if timeout is None else timeout
        return self.dut.frames.wait_for(lambda m: _from(m, SDO_RESPONSE_BASE + node_id), wait, mark) is not None

    def wait_bootup_at(self, node_id: int, after: Mark, timeout: float | None = None) -> can.Message | None:
        limit = self.dut.profile.timing.bootup_max_ms / 1000 if timeout is None else timeout
        return self.dut.frames.wait_for(lambda m: _from(m, HEARTBEAT_BASE + node_id) and bytes(m.data) == b"\x00",
                                        limit, after)

    def reset_communication(self, node_id: int) -> Mark:
        """NMT reset communication addressed to ``node_id`` (the device's active node-ID)."""
        return send_command(self.dut, "reset-communication", node_id=node_id)

    def moving_to(self, node_id: int) -> None:
        """A test is about to give the device ``node_id`` (255: unconfigured): custody looks there afterwards."""
        if node_id == UNCONFIGURED_NODE_ID:
            self.made_unconfigured = True
        else:
            self.moved_to.add(node_id)
        if self.on_move is not None:
            self.on_move(node_id)

    def configure_for(self, new_id: int) -> LssAnswer | None:
        """Into the configuration state and configure ``new_id`` (pending); the answer."""
        self.transition("configuration")
        self.moving_to(new_id)
        return self.master.configure_node_id(new_id)

    def apply_configured(self) -> Mark:
        """Make the configured node-ID active; the mark of the event that does, where a window for the device starts:
        CiA 305 v3: before NMT reset communication; a device that applies it only at power-on: store configuration
        and a power cycle, the power-on mark (not one before the power went off: issue 39)."""
        if self.applies_on_reset:
            self.leave()
            return self.reset_communication(self.node_id)
        return self._store_and_power_cycle()

    def apply_node_id(self, new_id: int) -> Mark:
        """Configure ``new_id`` instead of the node-ID in use and make it active; the mark of the event that makes it
        active (``apply_configured``)."""
        expect_success(self.configure_for(new_id), f"configure node-ID {new_id}")
        return self.apply_configured()

    def wait_unconfigured(self, since: Mark) -> str | None:
        """Wait, at most the profile's boot-up time after ``since`` (the reset or power-on), until the device shows
        it is unconfigured: it answers identify non-configured, a fastscan reset, or inquire node-ID with FFh.
        Returns how it showed it; None where it did not (a device with none of these services: None once the
        boot-up time passed without a boot-up at its old node-ID)."""
        deadline = Deadline(self.dut.profile.timing.bootup_max_ms / 1000, since=since.time)
        while not deadline.expired():
            with self.master.no_answer_expected():  # each look waits the LSS silence window, not the answer window
                if "identify_non_configured" in self.services:
                    if self.master.identify_non_configured():
                        return "identify non-configured answered"
                elif "fastscan" in self.services:
                    reset = self.master.request(LssCommand.FASTSCAN, bytes(4) + bytes([FASTSCAN_RESET_BIT, 0, 0]))
                    if self.master.answer(LssCommand.IDENTIFY_SLAVE, reset) is not None:
                        return "fastscan reset answered"
                elif {"switch_selective", "inquire_node_id"} <= self.services:
                    if self.master.switch_selective(self.address):
                        active = self.master.inquire_node_id()
                        self.leave()
                        if active == UNCONFIGURED_NODE_ID:
                            return "inquire node-ID answered FFh"
                else:
                    booted = self.wait_bootup_at(self.node_id, since, deadline.remaining())
                    return None if booted is not None else "no boot-up within the boot-up time"
        return None

    def _store_and_power_cycle(self) -> Mark:
        """Store (unless the device stores by itself) and power-cycle; the power-on mark."""
        if "node_id" not in self.auto_stored:
            expect_success(self.master.store_configuration(), "store configuration")
        self.leave()
        if self.power_cycle is None:
            raise AssertionError("the device applies a node-ID only at power-on and there is no power switch")
        return self.power_cycle()

    # -- put back ---------------------------------------------------------------------------------
    def _sent(self, command: int) -> bool:
        """Did the test send this LSS request?"""
        return bool(self.dut.frames.since(self.start, lambda m: not m.is_rx and m.arbitration_id == MASTER_COB_ID
                                          and bool(m.data) and m.data[0] == command))

    def changes(self) -> Changes:
        """What the test may have changed: the LSS configure and store requests it sent (the frame log)."""
        stored = self._sent(LssCommand.STORE_CONFIGURATION)
        node_id = self._sent(LssCommand.CONFIGURE_NODE_ID)
        bit_timing = self._sent(LssCommand.CONFIGURE_BIT_TIMING)
        auto = (node_id and "node_id" in self.auto_stored) or (bit_timing and "bit_timing" in self.auto_stored)
        return Changes(node_id=node_id or bool(self.moved_to) or self.made_unconfigured, bit_timing=bit_timing,
                       stored=stored or auto)

    def custody(self) -> LssCustody:
        """The search and put-back for this device (``dut/lss/lss_custody.py``)."""
        return LssCustody(self.dut, self.master, self.address, self.node_id, self.bit_index, self.power_cycle,
                          frozenset(self.moved_to), self.restore_hint)

    def put_back(self) -> str | None:
        """The device at its node-ID again, as found (node-ID and bit timing: active, pending and stored), wherever
        the test left it; None, or one line saying what could not be done, where the device is and what to run.
        Costs one frame where the test configured nothing."""
        problem = self.custody().put_back(self.changes())
        if problem is None and self.on_settled is not None:
            self.on_settled()
        return problem


def expect_success(answer: LssAnswer | None, what: str) -> LssAnswer:
    """An LSS answer with error 0, else AssertionError naming ``what`` and the answer."""
    problem = failure(answer, what)
    if problem or answer is None:  # (no answer is a problem too)
        raise AssertionError(problem)
    return answer


def _from(msg: can.Message, cob_id: int) -> bool:
    return msg.is_rx and msg.arbitration_id == cob_id and not msg.is_remote_frame
