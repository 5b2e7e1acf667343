"""Finding an LSS device wherever a test or a crash left it, and putting it back (CiA 305 v3.0.0).

A test may leave the device at another node-ID (active, or pending until the next reset), unconfigured (node-ID
FFh), in the LSS configuration state, with a pending bit rate, or with any of these stored. ``LssCustody`` looks
for it in this order, each look as long as the device owes its answer (``answer_window`` of the profile's
``sdo_response_max_ms`` / ``lss_response_ms``, ``bootup_max_ms`` for a boot-up):

1. at the node-ID it was found at and at every node-ID a test gave it (an SDO read of 1000h at each, sent at once);
2. by LSS: selected by its LSS address (switch state selective; its active node-ID from inquire node-ID), found by
   fastscan with its known address, or identified as non-configured;
3. after NMT reset communication addressed to each of those node-IDs (a pending node-ID applied);
4. after a power cycle, where there is a power switch (what it stored applied).

Then it configures the node-ID and bit timing the device was found with and applies the node-ID the way the
device takes it: at NMT reset communication (CiA 305 v3), on leaving the configuration state (unconfigured), or
from what it stored at a new boot-up (a power cycle: the WDGA's "new boot-up", M §8.2.4). It stores only what a
test stored (or what a power-on must find). A device it cannot bring back is described in one line: where it is
and what to run (``where``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import can

from encoder_conformance.cia.cia301 import (
    HEARTBEAT_BASE,
    SDO_REQUEST_BASE,
    SDO_RESPONSE_BASE,
)
from encoder_conformance.cia.cia305 import UNCONFIGURED_NODE_ID, LssState
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.lss.lss_master import LssAddress, LssAnswer, LssMaster
from encoder_conformance.dut.nmt.commands import send_in_custody
from encoder_conformance.dut.sdo.sdo_frames import upload_request


@dataclass(frozen=True)
class Changes:
    """What a test (or a run cut short) may have changed through LSS."""

    node_id: bool = True
    bit_timing: bool = True
    stored: bool = True

    @property
    def any(self) -> bool:
        return self.node_id or self.bit_timing or self.stored


@dataclass(frozen=True)
class Found:
    """Where the device was found: its active node-ID (FFh unconfigured; None: answers LSS, node-ID unknown)."""

    node_id: int | None
    how: str
    selected: bool = False  # in the LSS configuration state now


@dataclass
class LssCustody:
    """One device's LSS put-back: ``target`` node-ID and ``bit_index`` as found, the places to look."""

    dut: DeviceLink
    master: LssMaster
    address: LssAddress
    target: int
    bit_index: int | None
    power_cycle: Callable[[], Mark] | None = None  # off, on, woken; the power-on mark (dut/bench/power_on.py)
    candidates: frozenset[int] = frozenset()  # node-IDs a test gave the device
    restore_hint: str = ""  # the command that finishes the job later (shown where the device stays moved)

    @property
    def services(self) -> frozenset[str]:
        return frozenset(self.dut.profile.capabilities.lss)

    # -- looking --------------------------------------------------------------------------------
    def answers_at(self, node_id: int, timeout: float | None = None) -> bool:
        """Does a node answer an SDO read of 1000h at ``node_id`` (within the SDO answer window)?"""
        mark = self.dut.frames.mark()
        self.dut.network.send_message(SDO_REQUEST_BASE + node_id, upload_request(0x1000, 0))
        wait = self.dut.sdo_timeout if timeout is None else timeout
        return self.dut.frames.wait_for(lambda m: _from(m, SDO_RESPONSE_BASE + node_id), wait, mark) is not None

    def _others(self) -> list[int]:
        return sorted(set(self.candidates) - {self.target, UNCONFIGURED_NODE_ID})

    def answering(self, node_ids: list[int]) -> int | None:
        """The node-ID of ``node_ids`` that answers an SDO read of 1000h, all asked at once and the answer waited
        for the SDO answer window (it ends when one comes: the device owes its answer wherever it is)."""
        mark = self.dut.frames.mark()
        for node_id in node_ids:
            self.dut.network.send_message(SDO_REQUEST_BASE + node_id, upload_request(0x1000, 0))
        responses = [SDO_RESPONSE_BASE + node_id for node_id in node_ids]
        first = self.dut.frames.wait_for(lambda m: any(_from(m, r) for r in responses), self.dut.sdo_timeout, mark)
        return None if first is None else first.arbitration_id - SDO_RESPONSE_BASE

    def locate(self) -> Found | None:
        """Where the device is now (see the module docstring); None where no look found it."""
        node_id = self.answering([self.target, *self._others()])
        if node_id is not None:
            return Found(node_id, f"answers SDO at node-ID {node_id}")
        found = self._by_lss()
        if found is not None:
            return found
        mark = self.dut.frames.mark()
        for node_id in [self.target, *self._others()]:
            send_in_custody(self.dut, "reset-communication", node_id)
        boot = self._wait_bootup([self.target, *self._others()], mark)
        if boot is not None:
            return Found(boot, f"booted at node-ID {boot} after NMT reset communication")
        found = self._by_lss()
        if found is not None or self.power_cycle is None:
            return found
        mark = self._cycle()
        boot = self._wait_bootup([self.target, *self._others()], mark)
        if boot is not None:
            return Found(boot, f"booted at node-ID {boot} after a power cycle")
        return self._by_lss()

    def _by_lss(self) -> Found | None:
        """Selected by its LSS address, found by fastscan, or identified as non-configured."""
        for node_id in [self.target, *self._others()]:  # a device that takes LSS only in some NMT states
            send_in_custody(self.dut, "pre-operational", node_id)
        if "switch_selective" in self.services and self.master.switch_selective(self.address):
            active = self.master.inquire_node_id() if "inquire_node_id" in self.services else None
            state = "unconfigured" if active == UNCONFIGURED_NODE_ID else \
                f"at node-ID {active}" if active is not None else "at a node-ID it does not tell"
            return Found(active, f"selected by its LSS address: {state}", selected=True)
        if "fastscan" in self.services and self.master.fastscan(self.address.parts()) == self.address:
            return Found(UNCONFIGURED_NODE_ID, "unconfigured (found by fastscan)", selected=True)
        if "identify_non_configured" in self.services and self.master.identify_non_configured() > 0:
            return Found(UNCONFIGURED_NODE_ID, "unconfigured (identify non-configured answered)")
        return None

    def _wait_bootup(self, node_ids: Iterable[int], after: Mark) -> int | None:
        """The node-ID of the first boot-up at one of ``node_ids`` within the profile's boot-up time."""
        cob_ids = {HEARTBEAT_BASE + n for n in node_ids}
        boot = self.dut.frames.wait_for(lambda m: m.is_rx and m.arbitration_id in cob_ids and bytes(m.data) == b"\x00",
                                        self.dut.profile.timing.bootup_max_ms / 1000, after)
        return None if boot is None else boot.arbitration_id - HEARTBEAT_BASE

    def _cycle(self) -> Mark:
        """A power cycle; the power-on mark (a boot-up window starts there, not before the power went off)."""
        assert self.power_cycle is not None
        return self.power_cycle()

    # -- putting back ---------------------------------------------------------------------------
    def put_back(self, changes: Changes) -> str | None:
        """The device at its node-ID again with the node-ID and bit timing as found, active, pending and stored;
        None, or one line saying what could not be done, where the device is and what to run."""
        self.master.switch_global(LssState.WAITING)
        if not changes.any:
            return None
        found = self.locate()
        if found is None:
            return self.where(None, f"it answers neither at node-ID {self.target}, nor at "
                                    f"{self._others() or 'another node-ID a test gave it'}, nor to LSS")
        if found.node_id == self.target:
            return self._configure_as_found(changes, found)
        return self._move_back(found, changes)

    def _select(self, found: Found) -> bool:
        if found.selected:
            return True
        if found.node_id not in (None, UNCONFIGURED_NODE_ID):
            # LSS may be obeyed only in some NMT states, and a device that started itself is operational: its answer
            # shows the command was taken (pre-operational offers SDO)
            send_in_custody(self.dut, "pre-operational", found.node_id)
            self.answers_at(found.node_id)
        if "switch_selective" in self.services:
            return self.master.switch_selective(self.address)
        self.master.switch_global(LssState.CONFIGURATION)  # one device on the bench: global is the way
        return True

    def _configure(self, changes: Changes, store: bool) -> str | None:
        """In the configuration state: node-ID and bit timing as found, stored where ``store``."""
        problems = [failure(self.master.configure_node_id(self.target), f"configure node-ID {self.target}")]
        if changes.bit_timing and self.bit_index is not None:
            problems.append(failure(self.master.configure_bit_timing(self.bit_index),
                                    f"configure bit timing {self.bit_index}"))
        if store and "store_configuration" in self.services:
            problems.append(failure(self.master.store_configuration(), "store configuration"))
        return "; ".join(p for p in problems if p) or None

    def _configure_as_found(self, changes: Changes, found: Found) -> str | None:
        """At its node-ID: the pending node-ID and bit timing back to the ones in use (a later reset must not apply a
        test's), stored again where a test stored."""
        if not self._select(found):
            return f"the device does not answer to its LSS address {self.address.describe()}"
        problem = self._configure(changes, store=changes.stored)
        self.master.switch_global(LssState.WAITING)
        return problem

    def _move_back(self, found: Found, changes: Changes) -> str | None:
        """Elsewhere (or unconfigured): configure the node-ID as found and apply it; store and power-cycle only
        where the device takes a node-ID from its memory at a new boot-up."""
        if not self._select(found):
            return self.where(found, f"it does not answer to its LSS address {self.address.describe()}")
        problem = self._configure(changes, store=changes.stored)
        if problem:
            self.master.switch_global(LssState.WAITING)
            return self.where(found, f"{problem} (to put it back)")
        # the boot-up comes at the first of two events: leaving (an unconfigured device starts now, CiA 305) or the
        # reset communication (the pending node-ID applied, CiA 305 v3); frames are counted from the first
        mark = self.master.switch_global(LssState.WAITING)
        others = [n for n in [found.node_id] if n not in (None, UNCONFIGURED_NODE_ID)] or self._others()
        for node_id in others:
            send_in_custody(self.dut, "reset-communication", node_id)
        boot = self._wait_bootup([self.target, *others], mark)
        if boot == self.target or (boot is None and self.answers_at(self.target)):
            return None
        return self._new_boot_up(found, changes)

    def _new_boot_up(self, found: Found, changes: Changes) -> str | None:
        """The device takes the node-ID only from its memory at power-on: store it, switch off and on."""
        if not self._select(Found(found.node_id, found.how)):
            return self.where(found, f"it no longer answers to its LSS address {self.address.describe()}")
        problem = self._configure(changes, store=True)
        self.master.switch_global(LssState.WAITING)
        if problem:
            return self.where(found, f"{problem} (to put it back)")
        if self.power_cycle is None:
            return self.where(found, f"node-ID {self.target} is configured and stored; it becomes active at the next "
                                     "power-on (switch the device off and on)")
        boot = self._wait_bootup([self.target], self._cycle())
        if boot is None and not self.answers_at(self.target):
            return self.where(self.locate(), f"after store configuration and a power cycle it is not at node-ID "
                                             f"{self.target}")
        return None

    def where(self, found: Found | None, problem: str) -> str:
        """One line: what went wrong, where the device is, and the command that finishes the job."""
        place = found.how if found is not None else "not found"
        hint = f"; then: {self.restore_hint}" if self.restore_hint else ""
        return (f"LSS: {problem}; the device (LSS address {self.address.describe()}) is {place}; it belongs at "
                f"node-ID {self.target}{hint}")


def failure(answer: LssAnswer | None, what: str) -> str | None:
    """None for an LSS answer with error 0, else what went wrong with ``what``."""
    if answer is None:
        return f"{what}: no answer"
    if answer.error != 0:
        return f"{what}: error {answer.error} (specific {answer.specific})"
    return None


def _from(msg: can.Message, cob_id: int) -> bool:
    return msg.is_rx and msg.arbitration_id == cob_id and not msg.is_remote_frame
