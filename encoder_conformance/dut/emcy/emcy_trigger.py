"""Ways to make a device send an EMCY, for an encoder without RPDOs (the CTT forces one through a malformed RPDO).

- ``BenchError``: the bench's error stimulus (the simulator's control channel): any error, and its cause going
  away again (the error-reset EMCY).
- ``SyncLengthError``: where the profile has 1019h: the counter switched on (1019h > 0), then a SYNC without the
  counter byte: CiA 301 table 21 names the error 8240h "unexpected SYNC data length" (that the consumer sends
  it is CANopenNode's and the CTT's reading).
- ``HeartbeatTimeout``: where the profile has a writable 1016h sub 1: the device watches a producer the tester
  plays, which falls silent after one heartbeat: 8130h, or the code the profile's quirk documents.

Each trigger is prepared once (its settings through ``write``, which the caller makes a settings journal's, so
that they are put back) and fired as often as the test needs. A real device records each error in its history
(1003h): a bench run adds entries there.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import can

from encoder_conformance.basis import Basis
from encoder_conformance.cia.cia301 import (
    COB_ID_FRAME_29_BIT,
    COB_ID_INVALID,
    EMCY_BASE,
    EMCY_COB_ID,
    HEARTBEAT_BASE,
    HEARTBEAT_CONSUMER,
    SYNC_COB_ID,
    SYNC_COB_ID_OBJECT,
    SYNC_COUNTER_OVERFLOW,
    EmcyCode,
    NmtState,
)
from encoder_conformance.dut.bench.actuator import BenchActuator, ErrorStimulus
from encoder_conformance.dut.link.device import DeviceLink, answer_window
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.profile import quirk_effects as fx

Write = Callable[[int, int, bytes], None]
BENCH_CODE = 0x4200  # device temperature (CiA 301 table 21), as the WDGA sends it
BENCH_REGISTER_BITS = 0x08  # 1001h bit 3: temperature
BENCH_OTHER_CODE = 0x5000  # device hardware (CiA 301 table 21)
SYNC_OVERFLOW = 8  # 1019h while the SYNC-length trigger is prepared
HEARTBEAT_TIMEOUT_MS = 50  # 1016h time of the watched producer


@dataclass(frozen=True)
class EmcyCobId:
    """Where the device sends its EMCY (1014h, or 080h + node-ID without it); None while 1014h bit 31 is set."""

    can_id: int | None
    extended: bool = False

    @classmethod
    def of(cls, dut: DeviceLink) -> EmcyCobId:
        if dut.profile.entry(EMCY_COB_ID, 0) is None:
            return cls(EMCY_BASE + dut.node_id)
        value = dut.read_uint(EMCY_COB_ID)
        if value & COB_ID_INVALID:
            return cls(None)
        extended = bool(value & COB_ID_FRAME_29_BIT)
        return cls(value & (0x1FFFFFFF if extended else 0x7FF), extended)

    def matches(self, msg: can.Message) -> bool:
        return (msg.is_rx and not msg.is_remote_frame and msg.arbitration_id == self.can_id
                and msg.is_extended_id == self.extended)


def is_any_emcy(msg: can.Message) -> bool:
    """A frame on any pre-defined EMCY CAN-ID (081h-0FFh), from the device under test or not."""
    return msg.is_rx and not msg.is_remote_frame and not msg.is_extended_id and 0x81 <= msg.arbitration_id <= 0xFF


def emcy_code(msg: can.Message) -> int:
    return int.from_bytes(bytes(msg.data[0:2]), "little")


class EmcyTrigger:
    """Causes one error per ``fire``; ``code`` is the EMCY error code it causes."""

    name = ""
    code = 0
    basis: tuple[Basis, str] = ("cia", "CiA 301 §7.2.7 (an error the device detects is signalled by an EMCY)")
    #: can be fired many times a second (each a new error)
    repeatable = True
    #: ``clear`` makes the cause go away (the device owes the error-reset EMCY)
    clears = False
    _dut: DeviceLink

    def fire(self) -> Mark:
        raise NotImplementedError

    def clear(self) -> Mark:
        raise NotImplementedError(f"{self.name} cannot make the cause go away")

    def window_s(self) -> float:
        """How long the device may take to send the EMCY after ``fire`` (profile timing.emcy_response_max_ms)."""
        return self._dut.profile.timing.emcy_response_max_ms / 1000

    def answer_s(self) -> float:
        """How long to wait for an EMCY the device owes (the wait ends when it comes)."""
        return answer_window(self.window_s())

    def silence_s(self) -> float:
        """How long to watch for an EMCY the device must not send: what it would owe plus the tester's margin."""
        extra_s = self.window_s() - self._dut.profile.timing.emcy_response_max_ms / 1000  # a trigger's own delay
        return extra_s + self._dut.silence_window("emcy_response_max_ms")


class BenchError(EmcyTrigger):
    name = "the bench's error stimulus"
    code = BENCH_CODE
    clears = True

    def __init__(self, dut: DeviceLink, stimulus: ErrorStimulus) -> None:
        self._dut = dut
        self._stimulus = stimulus

    def fire(self, code: int = BENCH_CODE) -> Mark:
        """One error (``code``: another than the usual one, e.g. to tell entries of the history apart)."""
        mark = self._dut.frames.mark()
        self._stimulus.raise_emcy(code, BENCH_REGISTER_BITS)
        return mark

    def clear(self) -> Mark:
        mark = self._dut.frames.mark()
        self._stimulus.clear_emcy()
        return mark


class SyncLengthError(EmcyTrigger):
    name = f"a SYNC without its counter byte while 1019h = {SYNC_OVERFLOW}"
    code = EmcyCode.SYNC_LENGTH
    basis = ("inferred", "CiA 301 table 21 names EMCY 8240h 'unexpected SYNC data length'; that a SYNC consumer "
                         "sends it on a SYNC whose length does not match 1019h is CANopenNode's and the CTT's reading")

    def __init__(self, dut: DeviceLink, write: Write) -> None:
        self._dut = dut
        write(SYNC_COUNTER_OVERFLOW, 0, bytes([SYNC_OVERFLOW]))
        cob_id = dut.read_uint(SYNC_COB_ID_OBJECT) if dut.profile.entry(SYNC_COB_ID_OBJECT, 0) else SYNC_COB_ID
        self.sync_cob_id = cob_id & 0x7FF

    @staticmethod
    def available(dut: DeviceLink) -> str | None:
        """None where the device can be given this trigger, else why not."""
        entry = dut.profile.entry(SYNC_COUNTER_OVERFLOW, 0)
        if entry is None or not entry.writable:
            return "the profile has no writable 1019h (SYNC counter overflow value)"
        return None

    def fire(self) -> Mark:
        return self._dut.send(self.sync_cob_id, b"")


class HeartbeatTimeout(EmcyTrigger):
    repeatable = False  # each fire needs a heartbeat and the silence after it

    def __init__(self, dut: DeviceLink, write: Write) -> None:
        self._dut = dut
        self.producer = 0x7F if dut.node_id != 0x7F else 0x7E  # a node-ID the tester plays
        self.timeout_ms = HEARTBEAT_TIMEOUT_MS
        self.name = (f"a heartbeat-consumer time-out: 1016h.01 watches node {self.producer} for "
                     f"{HEARTBEAT_TIMEOUT_MS} ms, the tester sends one heartbeat of it")
        found = dut.profile.quirk(fx.HeartbeatConsumerEmcy)
        if found is not None:
            self.code = found.params.code
            self.basis = ("manual", f"{found.quirk.manual} (quirk {found.id}: time-out EMCY "
                                    f"{self.code:04X}h)")
        else:
            self.code = EmcyCode.HEARTBEAT
            self.basis = ("inferred", "CiA 301 table 21 names EMCY 8130h 'life guard error or heartbeat error'; "
                                      "CiA 301 §7.2.8.3.2.2 requires a heartbeat event, not an EMCY")
        write(HEARTBEAT_CONSUMER, 1, (self.producer << 16 | HEARTBEAT_TIMEOUT_MS).to_bytes(4, "little"))

    @staticmethod
    def available(dut: DeviceLink) -> str | None:
        entry = dut.profile.entry(HEARTBEAT_CONSUMER, 1)
        if not dut.profile.capabilities.heartbeat_consumer_entries or entry is None or not entry.writable:
            return "the profile has no writable heartbeat-consumer entry (1016h sub 1)"
        return None

    def fire(self) -> Mark:
        return self._dut.send(HEARTBEAT_BASE + self.producer, bytes([NmtState.OPERATIONAL]))

    def window_s(self) -> float:
        return HEARTBEAT_TIMEOUT_MS / 1000 + super().window_s()


def choose_trigger(dut: DeviceLink, bench: BenchActuator, write: Write,
                   repeatable: bool = False, clears: bool = False) -> EmcyTrigger | str:
    """The first trigger this bench and device offer (bench stimulus, SYNC length, heartbeat time-out) that can
    do what the test needs; else why there is none."""
    if bench.errors is not None:
        return BenchError(dut, bench.errors)
    reasons = [bench.why_not("errors")]
    if clears:
        return reasons[0]
    why = SyncLengthError.available(dut)
    if why is None:
        return SyncLengthError(dut, write)
    reasons.append(why)
    if repeatable:
        return "; ".join([*reasons, "a heartbeat-consumer time-out cannot be repeated fast enough"])
    why = HeartbeatTimeout.available(dut)
    if why is None:
        return HeartbeatTimeout(dut, write)
    return "; ".join([*reasons, why])
