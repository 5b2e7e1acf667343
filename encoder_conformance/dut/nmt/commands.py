"""Every NMT command the tester sends (CiA 301 v4.2.0 §7.2.8.3.1: COB-ID 000h, the command specifier and the node-ID,
0 for all nodes), and the resets that wait for the device to be back. The device's face offers them
(``dut.nmt.command``, ``dut.nmt.reset_node``); the DUT layer's own modules call them here, nowhere else builds the
frame (``tests/test_architecture.py``)."""

from __future__ import annotations

import can
import canopen

from encoder_conformance.cia.cia301 import HEARTBEAT_BASE, NMT_COB_ID, NMT_COMMAND_NAMES
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark, format_frames


def command_frame(command: str, node_id: int) -> bytes:
    """The NMT frame's two data bytes: the command specifier of ``command`` (a name of ``NMT_COMMAND_NAMES``) and the
    node-ID it addresses."""
    return bytes([NMT_COMMAND_NAMES[command], node_id])


def send_on(network: canopen.Network, command: str, node_id: int) -> None:
    """NMT command ``command`` to ``node_id`` on ``network``, whoever holds it (the probe's link too)."""
    network.send_message(NMT_COB_ID, command_frame(command, node_id))


def send_command(dut: DeviceLink, command: str, node_id: int | None = None) -> Mark:
    """Send an NMT command (to the device, or ``node_id``; 0 = all). Returns a mark before it."""
    return dut.send(NMT_COB_ID, command_frame(command, dut.node_id if node_id is None else node_id))


def send_in_custody(dut: DeviceLink, command: str, node_id: int) -> Mark:
    """An NMT command to ``node_id`` also while the run is stopping or the device counts as lost (custody may always
    talk). Returns a mark before it."""
    mark = dut.frames.mark()
    send_on(dut.network, command, node_id)
    return mark


def reset_and_reach(dut: DeviceLink) -> bool:
    """NMT reset node; True once a boot-up or an SDO answer shows the node is there."""
    mark = send_command(dut, "reset-node")
    return dut.wait_bootup(mark) is not None or dut.responds()


def reset_node_and_wait(dut: DeviceLink) -> can.Message:
    """NMT reset node; returns the boot-up frame or raises with the trace."""
    mark = send_command(dut, "reset-node")
    boot = dut.wait_bootup(mark)
    if boot is None:
        raise AssertionError(
            f"no boot-up ({HEARTBEAT_BASE + dut.node_id:03X}h... [1] 00) within "
            f"{dut.profile.timing.bootup_max_ms:.0f} ms after reset node\n"
            f"last frames:\n{format_frames(dut.frames.last(10))}"
        )
    return boot
