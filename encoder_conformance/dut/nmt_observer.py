"""Observe NMT states through the heartbeat (CiA 301 §7.2.8.3.2.2)."""

from __future__ import annotations

from .device import NMT_COMMANDS, STATE_NAMES, DeviceUnderTest
from .frames import Mark, format_frames

COMMAND_TARGET = {"start": 0x05, "stop": 0x04, "pre-operational": 0x7F}


class NmtObserver:
    """Sends NMT commands and waits until the heartbeat reports the expected state."""

    def __init__(self, dut: DeviceUnderTest, period_ms: int) -> None:
        self.dut = dut
        self.period_ms = period_ms

    @property
    def window_s(self) -> float:
        """How long a state change may take to show: settle time plus two heartbeat periods."""
        return (self.dut.profile.timing.nmt_settle_ms + 2 * self.period_ms) / 1000

    def expect_state(self, after: Mark, state: int, why: str) -> None:
        if self.dut.wait_heartbeat(after, self.window_s, state=state) is None:
            seen = self.dut.frames.since(after, lambda m: m.arbitration_id == 0x700 + self.dut.node_id)
            raise AssertionError(
                f"{why}: expected heartbeat state {state:02X}h ({STATE_NAMES.get(state)}) within "
                f"{self.window_s * 1000:.0f} ms; heartbeats seen:\n{format_frames(seen[-6:]) or '  none'}"
            )

    def command(self, name: str, node_id: int | None = None) -> Mark:
        if name not in NMT_COMMANDS:
            raise ValueError(f"unknown NMT command {name!r}")
        return self.dut.nmt(name, node_id)

    def go_to(self, state_name: str) -> None:
        """Bring the device into pre-operational, operational or stopped and confirm it."""
        command = {"pre-operational": "pre-operational", "operational": "start", "stopped": "stop"}[state_name]
        mark = self.command(command)
        self.expect_state(mark, COMMAND_TARGET[command], f"entering {state_name}")
