"""Finding LSS slaves on a bench (CiA 305): every unconfigured device, one device's revision, error words.

A scan changes nothing in the devices: each fastscan leaves the slave it found in configuration state,
where it no longer takes part, so the next fastscan finds the next one; at the end one switch state
global puts them all back in waiting state. Each fastscan first tries the previous device's vendor,
product, revision and serial + 1 (one step each), which finds a batch of units in a few steps apiece.
An answer later than the response window misleads a step (it counts for the next one); a fastscan or
a bisection spoiled that way is noticed (nobody found although devices answered; the revision found
does not answer) and repeated, a scan's fastscan with the window doubled (up to ``WIDEST_WINDOW`` times).
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import can

from encoder_conformance.cia.cia305 import (
    ERROR_MANUFACTURER,
    ERROR_NONE,
    ERROR_OUT_OF_RANGE,
    ERROR_STORE_ACCESS,
    IDENTIFY_RANGE_COMMANDS,
    SLAVE_COB_ID,
    LssCommand,
    LssState,
)
from encoder_conformance.dut.lss.lss_master import LssAddress, LssAnswer, LssMaster

#: a loop guard: more unconfigured devices than a network has node-IDs is a device that keeps answering
MAX_DEVICES = 127
FULL_RANGE = (0, 0xFFFFFFFF)
#: a fastscan whose reset was answered but that found nobody (an answer later than the window misled a step,
#: or a known part matches none of the devices) is tried this often more before the scan gives up
SPOILED_RETRIES = 3
#: bisections tried before find_revision gives up (each is checked by identifying the revision found)
BISECTIONS = 2
#: after a fastscan that found nobody, answers are still looked for this many response windows
LATE_WINDOWS = 2
#: a fastscan spoiled by answers later than the window is tried again with the window doubled, up to this many
#: times the one given (--response-ms): the devices' answers show what they need (a loaded bench PC or link)
WIDEST_WINDOW = 8

Progress = Callable[[int, LssAddress], None]


@dataclass
class ScanResult:
    """What a scan found, how long it took (bus already open) and how many LSS frames it sent."""

    devices: list[LssAddress] = field(default_factory=list)
    seconds: float = 0.0
    frames: int = 0
    repeated: LssAddress | None = None  # found twice: it did not stay in configuration state (list incomplete)
    unresolved: bool = False  # unconfigured devices answered that no fastscan could find (list incomplete)
    widened_to_s: float | None = None  # the response window the late answers made the scan take, if it grew


def scan_unconfigured(master: LssMaster, known: Sequence[int | None] = (None, None, None, None),
                      progress: Progress | None = None) -> ScanResult:
    """Every unconfigured device in waiting state (repeated fastscan); all are in waiting state afterwards."""
    start, steps = time.perf_counter(), master.steps
    result = ScanResult()
    master.switch_global(LssState.WAITING)  # a device an earlier session left in configuration state takes part
    guess: tuple[int | None, ...] = (None, None, None, None)
    spoiled = 0
    given_s = master.response_s
    try:
        while len(result.devices) < MAX_DEVICES:
            mark = master.frames.mark()
            address = master.fastscan(known, guess)
            if address is None:
                # nobody answered at all, not even later than the window (a loaded host or link): none left
                if master.frames.wait_for(_scan_answer, LATE_WINDOWS * master.response_s, mark) is None:
                    break
                spoiled += 1
                if spoiled > SPOILED_RETRIES:
                    result.unresolved = True
                    break
                if master.response_s < WIDEST_WINDOW * given_s:  # answers came after the window: give them more
                    master.response_s = min(2 * master.response_s, WIDEST_WINDOW * given_s)
                    result.widened_to_s = master.response_s
                continue
            spoiled = 0
            if address in result.devices:
                result.repeated = address
                break
            result.devices.append(address)
            # units of one batch mostly share vendor, product and revision, and often have consecutive serials
            guess = (address.vendor, address.product, address.revision, (address.serial + 1) & 0xFFFFFFFF)
            if progress is not None:
                progress(len(result.devices), address)
    finally:
        master.response_s = given_s
        master.switch_global(LssState.WAITING)
    result.seconds = time.perf_counter() - start
    result.frames = master.steps - steps
    return result


def _scan_answer(msg: can.Message) -> bool:
    return msg.is_rx and msg.arbitration_id == SLAVE_COB_ID and msg.data[:1] == bytes([LssCommand.IDENTIFY_SLAVE])


def any_identified(master: LssMaster, low: LssAddress, high: LssAddress) -> bool:
    """Identify remote slave (vendor and product exact, revision and serial in [low, high]): did any device
    answer? Returns at the first answer; only a silence costs the whole response window."""
    mark = master.frames.mark()
    values = (low.vendor, low.product, low.revision, high.revision, low.serial, high.serial)
    for command, value in zip(IDENTIFY_RANGE_COMMANDS, values, strict=True):
        master.request(command, struct.pack("<I", value))
    return master.answer(LssCommand.IDENTIFY_SLAVE, mark, master.response_s) is not None


def find_revision(master: LssMaster, vendor: int, product: int, serial: int,
                  revisions: tuple[int, int] = FULL_RANGE) -> int | None:
    """The revision of the device with ``vendor``, ``product`` and ``serial`` by range bisection (about 32
    identify steps for the full range); None if no device in the range answers."""
    low, high = revisions

    def answered(first: int, last: int) -> bool:
        return any_identified(master, LssAddress(vendor, product, first, serial),
                              LssAddress(vendor, product, last, serial))

    if not answered(low, high):
        return None
    for _attempt in range(BISECTIONS):
        first, last = low, high
        while first < last:
            middle = (first + last) // 2
            if answered(first, middle):
                last = middle
            else:
                first = middle + 1
        if answered(first, first):  # a late answer can have sent the bisection the wrong way
            return first
    return None


#: what error 1 means for each configuration service (CiA 305)
_ERROR_ONE: dict[int, str] = {
    LssCommand.CONFIGURE_NODE_ID: "node-ID out of range",
    LssCommand.CONFIGURE_BIT_TIMING: "bit timing not supported",
    LssCommand.STORE_CONFIGURATION: "store configuration not supported",
}


def error_text(command: int, answer: LssAnswer) -> str:
    """A configure / store answer in words: 'done', 'node-ID out of range (error 1)', ..."""
    if answer.error == ERROR_NONE:
        return "done"
    if answer.error == ERROR_OUT_OF_RANGE:
        return f"{_ERROR_ONE.get(command, 'refused')} (error 1)"
    if answer.error == ERROR_STORE_ACCESS and command == LssCommand.STORE_CONFIGURATION:
        return "storage media access error (error 2)"
    if answer.error == ERROR_MANUFACTURER:
        return f"manufacturer-specific error, code {answer.specific} = 0x{answer.specific:02X} (error FFh)"
    return f"error {answer.error} (reserved in CiA 305)"
