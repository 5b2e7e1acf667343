"""The device under test seen through LSS (CiA 305): its LSS address, node-ID and bit rate as found,
the services its profile declares, and the put-back after a test that changed its node-ID.

A test may move the device to another node-ID or make it unconfigured (255); ``put_back`` brings it
to the node-ID it was found at, whatever state a failed or interrupted test left it in: leave the
configuration state, and if the node does not answer at its node-ID, select it by its LSS address,
configure the original node-ID and apply it (NMT reset communication, or store + power cycle on a
device that applies a node-ID only at power-on).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import can

from ..cia305 import BIT_TIMING_TABLE_0, MASTER_COB_ID, UNCONFIGURED_NODE_ID, LssCommand, LssState
from ..profile import quirk_effects as fx
from .device import DeviceUnderTest
from .frames import Mark
from .lss_master import LssAddress, LssAnswer, LssMaster
from .sdo_frames import upload_request


def table_index(bitrate: int, table: dict[int, int] = BIT_TIMING_TABLE_0) -> int | None:
    """LSS table-0 index of a bit rate (None: not in the table)."""
    return next((index for index, rate in table.items() if rate == bitrate), None)


@dataclass
class LssDevice:
    """LSS view of the device under test."""

    dut: DeviceUnderTest
    master: LssMaster
    address: LssAddress
    bit_index: int | None  # the table-0 index of the bit rate in use, where known
    power_cycle: Callable[[], None] | None = None  # a bench power switch, where there is one
    moved_to: set[int] = field(default_factory=set)  # node-IDs a test gave the device
    made_unconfigured: bool = False
    start: Mark | None = None  # before the test's first LSS frame

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

    def _select_within(self, seconds: float) -> bool:
        """Select the device, retrying while it may still be starting (after a power cycle)."""
        deadline = time.monotonic() + seconds
        while not self.select():
            if time.monotonic() > deadline:
                return False
        return True

    def leave(self) -> Mark:
        return self.master.switch_global(LssState.WAITING)

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
        self.dut.network.send_message(0x600 + node_id, upload_request(0x1000, 0))
        wait = self.dut.sdo_timeout if timeout is None else timeout
        return self.dut.frames.wait_for(lambda m: _from(m, 0x580 + node_id), wait, mark) is not None

    def wait_bootup_at(self, node_id: int, after: Mark, timeout: float | None = None) -> can.Message | None:
        limit = self.dut.profile.timing.bootup_max_ms / 1000 if timeout is None else timeout
        return self.dut.frames.wait_for(lambda m: _from(m, 0x700 + node_id) and bytes(m.data) == b"\x00",
                                        limit, after)

    def reset_communication(self, node_id: int) -> Mark:
        """NMT reset communication addressed to ``node_id`` (the device's active node-ID)."""
        return self.dut.nmt("reset-communication", node_id=node_id)

    def apply_node_id(self, new_id: int) -> Mark:
        """Configure ``new_id`` instead of the node-ID in use and make it active; returns a mark before it
        becomes active. On a device that applies it only at power-on: store configuration and a power cycle."""
        assert self.select(), f"switch state selective to {self.address.describe()}: no answer (44h)"
        if new_id == UNCONFIGURED_NODE_ID:
            self.made_unconfigured = True
        else:
            self.moved_to.add(new_id)
        expect_success(self.master.configure_node_id(new_id), f"configure node-ID {new_id}")
        if self.applies_on_reset:
            self.leave()
            return self.reset_communication(self.node_id)
        return self._store_and_power_cycle()

    def _store_and_power_cycle(self) -> Mark:
        """Store (unless the device stores by itself) and power-cycle; a mark before the power went off."""
        if "node_id" not in self.auto_stored:
            expect_success(self.master.store_configuration(), "store configuration")
        self.leave()
        if self.power_cycle is None:
            raise AssertionError("the device applies a node-ID only at power-on and there is no power switch")
        mark = self.dut.frames.mark()
        self.power_cycle()
        return mark

    # -- put back ----------------------------------------------------------------------------------
    def _sent(self, command: int) -> bool:
        """Did the test send this LSS request?"""
        return bool(self.dut.frames.since(self.start, lambda m: not m.is_rx and m.arbitration_id == MASTER_COB_ID
                                          and bool(m.data) and m.data[0] == command))

    def put_back(self) -> str | None:
        """The device at its node-ID again, as found, with nothing else pending; None, or what could not be
        put back. Costs a few frames where the test only configured values it never applied."""
        self.leave()
        if not self._sent(LssCommand.CONFIGURE_NODE_ID) and not self._sent(LssCommand.CONFIGURE_BIT_TIMING):
            return None
        moved = bool(self.moved_to) or self.made_unconfigured
        if not moved or self.answers_at(self.node_id, timeout=self.dut.sdo_silence_s):
            return self._configure_as_found()
        return self.recover()

    def recover(self) -> str | None:
        """The device does not answer at its node-ID (moved, or unconfigured): select it by its LSS address,
        configure its node-ID and apply it; None, or what could not be done."""
        if not self._select_within(self.dut.profile.timing.bootup_max_ms / 1000):
            return f"the device does not answer at node-ID {self.node_id} nor to its LSS address"
        active = self.master.inquire_node_id() if "inquire_node_id" in self.services else None
        problem = failure(self.master.configure_node_id(self.node_id), f"configure node-ID {self.node_id}")
        if problem:
            return f"{problem} (to put the device back)"
        if self.applies_on_reset:
            mark = self.leave()  # an unconfigured device starts now
            for node_id in {active, *self.moved_to} - {None, UNCONFIGURED_NODE_ID}:
                mark = self.reset_communication(node_id)  # type: ignore[arg-type]
        else:
            try:
                mark = self._store_and_power_cycle()
            except AssertionError as exc:
                return f"node-ID {self.node_id} configured and stored, not applied: {exc}; switch the device off and on"
        if self.wait_bootup_at(self.node_id, mark) is None and not self.answers_at(self.node_id):
            return f"after configure node-ID {self.node_id} the device does not answer at it"
        return None

    def _configure_as_found(self) -> str | None:
        """Pending node-ID and bit timing back to the ones in use (a later reset must not apply a test's)."""
        if not self.select():
            return f"the device does not answer to its LSS address {self.address.describe()}"
        problems = []
        if self._sent(LssCommand.CONFIGURE_NODE_ID):
            problems.append(failure(self.master.configure_node_id(self.node_id), f"configure node-ID {self.node_id}"))
        if self._sent(LssCommand.CONFIGURE_BIT_TIMING) and self.bit_index is not None:
            problems.append(failure(self.master.configure_bit_timing(self.bit_index),
                                    f"configure bit timing {self.bit_index}"))
        if self._sent(LssCommand.STORE_CONFIGURATION):  # what the test stored must not wait for a power cycle
            problems.append(failure(self.master.store_configuration(), "store configuration"))
        self.leave()
        return "; ".join(p for p in problems if p) or None


def failure(answer: LssAnswer | None, what: str) -> str | None:
    """None for an LSS answer with error 0, else what went wrong with ``what``."""
    if answer is None:
        return f"{what}: no answer"
    if answer.error != 0:
        return f"{what}: error {answer.error} (specific {answer.specific})"
    return None


def expect_success(answer: LssAnswer | None, what: str) -> LssAnswer:
    """An LSS answer with error 0, else AssertionError naming ``what`` and the answer."""
    problem = failure(answer, what)
    if problem:
        raise AssertionError(problem)
    return answer  # type: ignore[return-value]


def _from(msg: can.Message, cob_id: int) -> bool:
    return msg.is_rx and msg.arbitration_id == cob_id and not msg.is_remote_frame
