"""What the start-up check's frames show when it failed: replies that break CiA 301, or another SDO client.

A device whose replies break CiA 301 (a multiplexer that is not the request's, a DLC other than 8) while only
this tester's requests are on the bus has been shown to be non-conformant: a FAIL with the clause. Only where
requests of another client were seen on the device's SDO channel (600h + node-ID, not sent by this tester) may
the replies be answers to it: the run could not test. A reply that answers a request the tester gave up on
(it sent its next request before any reply came) is a late answer to that request, not a broken one: on a
loaded machine a device may answer after the tester's timeout.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import can

from encoder_conformance.cia.cia301 import (
    SDO_ANSWER,
    SDO_REQUEST_BASE,
    SDO_RESPONSE_BASE,
    SdoClientCommand,
    SdoServerCommand,
)
from encoder_conformance.dut.sdo.sdo_frames import answers

#: CiA 301 v4.2.0 clauses a start-up reply can break
DLC_CLAUSE = "CiA 301 v4.2.0 §7.2.4.3.1 (SDO: every SDO frame has a DLC of 8)"
MUX_CLAUSES: dict[int, str] = {
    SdoClientCommand.INITIATE_DOWNLOAD:
        "CiA 301 v4.2.0 §7.2.4.3.3 (SDO download initiate: the response carries the request's multiplexer m)",
    SdoClientCommand.INITIATE_UPLOAD:
        "CiA 301 v4.2.0 §7.2.4.3.6 (SDO upload initiate: the response carries the request's multiplexer m)",
}
ABORT_CLAUSE = "CiA 301 v4.2.0 §7.2.4.3.17 (abort SDO transfer: m is the multiplexer of the transfer aborted)"
SHOWN = 4  # broken replies named in the verdict


@dataclass
class StartupFrames:
    """The start-up check's SDO frames, judged."""

    broken: list[tuple[str, str]] = field(default_factory=list)  # (what was seen, the clause it breaks)
    other_client: list[can.Message] = field(default_factory=list)  # requests this tester did not send

    @property
    def clauses(self) -> str:
        return "; ".join(dict.fromkeys(clause for _, clause in self.broken))

    def describe(self) -> str:
        lines = [seen for seen, _ in self.broken[:SHOWN]]
        more = f" (and {len(self.broken) - SHOWN} more)" if len(self.broken) > SHOWN else ""
        replies = "reply" if len(self.broken) == 1 else "replies"
        return (f"{len(self.broken)} SDO {replies} broke CiA 301 with only this tester's requests on the bus{more}:\n"
                + "\n".join(f"  {line}" for line in lines))


def _hex(data: bytes) -> str:
    return data.hex(" ").upper()


def judge(frames: list[can.Message], node_id: int) -> StartupFrames:
    """Judge every SDO reply of ``frames`` (the log since the check began) against the request before it."""
    found = StartupFrames()
    request: bytes | None = None
    replied = True
    given_up: list[bytes] = []  # requests followed by the next one before any reply came
    for msg in frames:
        if msg.is_remote_frame or msg.is_error_frame:
            continue
        data = bytes(msg.data)
        if msg.arbitration_id == SDO_REQUEST_BASE + node_id:
            if msg.is_rx:
                found.other_client.append(msg)
            else:
                if request is not None and not replied and len(request) >= 4 and request[0] >> 5 in MUX_CLAUSES:
                    given_up.append(request)  # an initiate: its late answer names its multiplexer
                request, replied = data, False
            continue
        if not msg.is_rx or msg.arbitration_id != SDO_RESPONSE_BASE + node_id:
            continue
        late = next((old for old in given_up if len(data) == 8 and data[1:4] == old[1:4] and answers(old, data)), None)
        if late is not None:
            given_up.remove(late)  # its one late answer
            continue
        replied = True
        if msg.dlc != 8:
            found.broken.append((f"reply {_hex(data)} with DLC {msg.dlc}", DLC_CLAUSE))
            continue
        if request is None or len(request) < 4:
            continue
        ccs, scs = request[0] >> 5, data[0] >> 5
        initiate_reply = ccs in MUX_CLAUSES and scs == SDO_ANSWER[ccs]
        if (initiate_reply or scs == SdoServerCommand.ABORT) and ccs in MUX_CLAUSES and data[1:4] != request[1:4]:
            clause = ABORT_CLAUSE if scs == SdoServerCommand.ABORT else MUX_CLAUSES[ccs]
            asked = f"{request[2]:02X}{request[1]:02X}h.{request[3]:02X}"
            got = f"{data[2]:02X}{data[1]:02X}h.{data[3]:02X}"
            found.broken.append((f"request {_hex(request)} ({asked}) answered {_hex(data)}: multiplexer {got}", clause))
    return found
