"""The probe's line to the device: SDO reads and writes that say what happened, NMT reset, a frame wait.

canopen's SDO client does the transfers (expedited, segmented, block); this module turns its exceptions into
values, because for the probe an abort is an answer, not an error.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import can
import canopen
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from encoder_conformance.cia.cia301 import HEARTBEAT_BASE
from encoder_conformance.config.bus import BusConfig
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.link import connection
from encoder_conformance.dut.link.frames import FrameLog, Mark
from encoder_conformance.dut.nmt.commands import send_on


@dataclass(frozen=True)
class Answer:
    """One SDO request's outcome: the data read (or b"" for a write), an abort code, or no answer."""

    data: bytes | None = None
    abort: int | None = None

    @property
    def ok(self) -> bool:
        return self.data is not None

    @property
    def silent(self) -> bool:
        return self.data is None and self.abort is None

    def describe(self) -> str:
        if self.abort is not None:
            return f"abort {self.abort:08X}h"
        return "no answer" if self.data is None else self.data.hex(" ").upper() or "accepted"


def upload(index: int, sub: int, answer: Answer) -> str:
    """The frames a finding rests on, e.g. 'upload 6501h.03 -> abort 08000024h'."""
    return f"upload {index:04X}h.{sub:02X} -> {answer.describe()}"


def download(index: int, sub: int, data: bytes, answer: Answer) -> str:
    """'download 1800h.02 F1 -> accepted': the request's data and the answer."""
    return f"download {index:04X}h.{sub:02X} {data.hex(' ').upper()} -> {answer.describe()}"


class ProbeLink:
    """A canopen network with one node (no object dictionary: the probe reads raw bytes) and its frame log."""

    def __init__(self, bus: BusConfig, node_id: int, sdo_timeout_s: float) -> None:
        self.frames = FrameLog()
        self.network = connection.connect(bus.kwargs, bus.describe(), self.frames)
        self.node_id = node_id
        self.node = canopen.RemoteNode(node_id, canopen.ObjectDictionary())
        self.network.add_node(self.node)
        self.node.sdo.RESPONSE_TIMEOUT = sdo_timeout_s
        self.node.sdo.MAX_RETRIES = 1  # canopen counts attempts: 1 sends once (0 would retry for ever)
        self.requests = 0  # SDO requests made (for the summary)

    def close(self) -> None:
        connection.disconnect(self.network)

    def read(self, index: int, sub: int) -> Answer:
        self.requests += 1
        try:
            return Answer(data=bytes(self.node.sdo.upload(index, sub)))
        except SdoAbortedError as exc:
            return Answer(abort=exc.code)
        except SdoCommunicationError:
            return Answer()

    def first_answer(self, timeout_s: float) -> Answer:
        """1000h read until the device answers (it may still be booting) or ``timeout_s`` has passed."""
        deadline = Deadline(timeout_s)
        while True:
            answer = self.read(0x1000, 0)
            if not answer.silent or deadline.expired():
                return answer

    def write(self, index: int, sub: int, data: bytes, force_segment: bool = False) -> Answer:
        self.requests += 1
        try:
            self.node.sdo.download(index, sub, data, force_segment=force_segment)
        except SdoAbortedError as exc:
            return Answer(abort=exc.code)
        except SdoCommunicationError:
            return Answer()
        return Answer(data=b"")

    def block_read(self, index: int, sub: int) -> Answer:
        """A block upload (CiA 301 §7.2.4.3.10): the device may refuse it (abort) or not know it (no answer)."""
        self.requests += 1
        try:
            with self.node.sdo.open(index, sub, "rb", block_transfer=True) as stream:
                return Answer(data=bytes(stream.read()))
        except SdoAbortedError as exc:
            return Answer(abort=exc.code)
        except SdoCommunicationError:
            return Answer()

    # -- NMT and error control ---------------------------------------------------------------------
    def nmt_command(self, command: str) -> Mark:
        """NMT command ``command`` (start, reset-node, ...) to the device, through dut/nmt/; a mark before it."""
        mark = self.frames.mark()
        send_on(self.network, command, self.node_id)
        return mark

    def is_error_control(self, msg: can.Message) -> bool:
        return msg.is_rx and msg.arbitration_id == HEARTBEAT_BASE + self.node_id and not msg.is_remote_frame \
            and len(msg.data) == 1

    def boot_up(self, after: Mark, timeout_s: float) -> can.Message | None:
        """The boot-up message (one byte 00h on 700h + node-ID) after ``after``."""
        return self.frames.wait_for(lambda m: self.is_error_control(m) and m.data[0] == 0, timeout_s, after)

    def wait(self, predicate: Callable[[can.Message], bool], timeout_s: float) -> can.Message | None:
        return self.frames.wait_for(predicate, timeout_s)

    def guard(self, timeout_s: float) -> can.Message | None:
        """A node-guarding request (RTR on 700h + node-ID) and the answer to it, if any."""
        mark = self.frames.mark()
        self.network.send_message(HEARTBEAT_BASE + self.node_id, b"", remote=True)
        return self.frames.wait_for(self.is_error_control, timeout_s, mark)
