"""Observe a device's NMT state: through its heartbeat, or, without one, through its services.

CiA 301 §7.2.8.3.2.2: the heartbeat carries the state byte. A device with neither heartbeat
nor node guarding (the legacy POSITAL) still shows its state by what it answers: no SDO in
stopped, SDO but no PDO in pre-operational, SYNC-driven PDOs in operational (§7.3.2.2).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from encoder_conformance.cia.cia301 import NMT_COMMAND_NAMES, NMT_COMMAND_TARGET, STATE_NAMES
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.nmt.commands import send_command
from encoder_conformance.dut.nmt.heartbeat_state import state_change_s
from encoder_conformance.dut.nmt.nmt_states import confirm
from encoder_conformance.dut.nmt.persistent_error import raise_if_held_out_of
from encoder_conformance.dut.sdo.sdo_frames import upload_request

#: the state each state-changing command leads to, by the suites' names for the commands
COMMAND_TARGET = {name: int(NMT_COMMAND_TARGET[command]) for name, command in NMT_COMMAND_NAMES.items()
                  if command in NMT_COMMAND_TARGET}
ENTER = {"pre-operational": "pre-operational", "operational": "start", "stopped": "stop"}


class NmtObserver(Protocol):
    dut: DeviceLink
    method: str

    @property
    def window_s(self) -> float: ...

    def expect_state(self, after: Mark, state: int, why: str) -> None: ...

    def expect_not_state(self, after: Mark, state: int, why: str) -> None: ...


class _Commands:
    """Sending NMT commands and bringing the device into a state, shared by both observers."""

    dut: DeviceLink
    expect_state: Callable[[Mark, int, str], None]  # each observer's own (NmtObserver.expect_state)

    def command(self, name: str, node_id: int | None = None) -> Mark:
        if name not in NMT_COMMAND_NAMES:
            raise ValueError(f"unknown NMT command {name!r}")
        return send_command(self.dut, name, node_id)

    def go_to(self, state_name: str) -> None:
        """Bring the device into pre-operational, operational or stopped and confirm it (the heartbeat at the period
        the test set, see ``nmt_states.reach`` for a test that has not; or the services without one)."""
        command = ENTER[state_name]
        mark = self.command(command)
        self.expect_state(mark, COMMAND_TARGET[command], f"entering {state_name}")


class HeartbeatObserver(_Commands):
    """Waits until the heartbeat reports the expected state."""

    method = "heartbeat state byte"

    def __init__(self, dut: DeviceLink, period_ms: int) -> None:
        self.dut = dut
        self.period_ms = period_ms

    @property
    def window_s(self) -> float:
        """How long a state change may take to show: settle time plus two heartbeat periods."""
        return state_change_s(self.dut, self.period_ms)

    def expect_state(self, after: Mark, state: int, why: str) -> None:
        confirm(self.dut, after, state, self.period_ms, why)  # names the state the heartbeat reports instead

    def expect_not_state(self, after: Mark, state: int, why: str) -> None:
        hit = self.dut.wait_heartbeat(after, self.window_s, state=state)
        assert hit is None, f"{why}: the heartbeat reported {state:02X}h ({STATE_NAMES.get(state)})"


class ServiceObserver(_Commands):
    """Infers the state from SDO answers and SYNC-driven TPDOs (for devices without heartbeat)."""

    method = "SDO answers and SYNC-driven TPDOs"

    def __init__(self, dut: DeviceLink, tpdo_comm_index: int) -> None:
        self.dut = dut
        self.tpdo_cob_id = dut.read_uint(tpdo_comm_index, 1) & 0x7FF
        every = dut.read_uint(tpdo_comm_index, 2)
        self.syncs_per_pdo = every if 1 <= every <= 240 else 1

    @property
    def window_s(self) -> float:
        timing = self.dut.profile.timing
        return (timing.nmt_settle_ms + 2 * timing.sdo_response_max_ms) / 1000 + self.dut.sdo_timeout

    def observe(self) -> int:
        """The state the device shows now: 04h (no SDO), 05h (TPDO on SYNC) or 7Fh.

        Each absence is watched for what the device owes plus the tester's margin (silence windows).
        """
        if self.dut.sdo_request(upload_request(0x1000, 0), timeout=self.dut.sdo_silence_s) is None:
            return 0x04
        mark = self.dut.frames.mark()
        for _ in range(self.syncs_per_pdo):
            self.dut.send_sync()
        pdo = self.dut.frames.wait_for(
            lambda m: m.is_rx and m.arbitration_id == self.tpdo_cob_id, self.dut.pdo_silence_s, mark
        )
        return 0x05 if pdo is not None else 0x7F

    def _observe_until(self, state: int) -> int:
        deadline = Deadline(self.window_s)
        while True:
            observed = self.observe()
            if observed == state or deadline.expired():
                return observed

    def expect_state(self, after: Mark, state: int, why: str) -> None:
        observed = self._observe_until(state)
        if observed != state:
            raise_if_held_out_of(self.dut, state, why)
        assert observed == state, (
            f"{why}: expected {state:02X}h ({STATE_NAMES.get(state)}), the device behaves as "
            f"{observed:02X}h ({STATE_NAMES.get(observed)}) (observed by {self.method})"
        )

    def expect_not_state(self, after: Mark, state: int, why: str) -> None:
        observed = self.observe()
        assert observed != state, f"{why}: the device behaves as {STATE_NAMES.get(state)} ({self.method})"
