"""The SYNC consumer's objects: the SYNC COB-ID 1005h (CiA 301 §7.5.2, 1005h) and the SYNC length check.

Behaviours:
- ``SyncCobIdRules``, a write gate on 1005h: bit 30 (the device generates SYNC) is refused with 06090030h by a
  device that cannot produce SYNC (capabilities.sync_producer not true; its variant ``sync_producer`` accepts it
  where the profile says "may", and ``sync_producer.SyncProducer`` then sends SYNC every 1006h µs); a
  restricted CAN-ID (CiA 301 §7.3.5) is refused with 06090030h, unless the profile's quirk lets 1005h take any
  CAN-ID of a range. Bit 31 is "do not care" for 1005h: accepted.
- ``SyncConsumer``: which frame is a SYNC: the CAN-ID in 1005h bits 0-10 (bits 0-28 with bit 29), whatever bit 31.
- ``SyncLengthCheck``, where the profile has 1019h: a SYNC whose length does not match 1019h (DLC 1 with a
  counter, 0 without) records the error 8240h "unexpected SYNC data length" and sends its EMCY (CiA 301 table 21
  names the code; that a consumer sends it is CANopenNode's and the CTT's reading). A device without 1019h accepts
  any length (WDGA: its manual's SYNC has DLC 8).
"""

from __future__ import annotations

from collections.abc import Callable

import can

from encoder_conformance.cia.cia301 import (
    COB_ID_FRAME_29_BIT,
    COB_ID_SYNC_GENERATE,
    SYNC_COB_ID,
    SYNC_COB_ID_OBJECT,
    SYNC_COUNTER_OVERFLOW,
    EmcyCode,
    SdoAbortCode,
    is_restricted_can_id,
)
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.sim.engine.faults import breaks
from encoder_conformance.sim.engine.hooks import NodeHooks, Value
from encoder_conformance.sim.engine.nvm import Key
from encoder_conformance.sim.engine.sdo_server import SdoAbort

COMMUNICATION_ERROR_BIT = 0x10  # 1001h bit 4 (CiA 301 §7.5.2, 1001h)
Read = Callable[[int, int], int | None]


class SyncCobIdRules:
    def __init__(self, any_can_id: fx.SyncCobIdAnyCanId | None, can_produce: bool = False) -> None:
        self._any_can_id = any_can_id
        self._can_produce = can_produce

    def register(self, hooks: NodeHooks) -> None:
        hooks.gates.append(self.gate)

    def gate(self, key: Key, value: Value) -> None:
        if key != (SYNC_COB_ID_OBJECT, 0) or not isinstance(value, int):
            return
        if value & COB_ID_SYNC_GENERATE and not self.generate_accepted():
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)
        if not value & COB_ID_FRAME_29_BIT and not self.can_id_accepted(value & 0x7FF):
            raise SdoAbort(SdoAbortCode.VALUE_INVALID)

    def generate_accepted(self) -> bool:
        return self._can_produce

    def can_id_accepted(self, can_id: int) -> bool:
        if self._any_can_id is not None:
            return self._any_can_id.min <= can_id <= self._any_can_id.max
        return not is_restricted_can_id(can_id)


class SyncConsumer:
    """Tells the node which received frame is a SYNC."""

    def __init__(self, read: Read) -> None:
        self._read = read

    def is_sync(self, msg: can.Message) -> bool:
        if msg.is_remote_frame:
            return False
        return msg.arbitration_id == self.cob_id() and msg.is_extended_id == self._extended()

    def cob_id(self) -> int:
        value = self._read(SYNC_COB_ID_OBJECT, 0)
        if value is None:
            return SYNC_COB_ID
        return value & 0x1FFFFFFF if value & COB_ID_FRAME_29_BIT else value & 0x7FF

    def _extended(self) -> bool:
        value = self._read(SYNC_COB_ID_OBJECT, 0)
        return bool(value is not None and value & COB_ID_FRAME_29_BIT)


class SyncLengthCheck:
    """A SYNC of the wrong length for 1019h records error 8240h (with its EMCY)."""

    def __init__(self, read: Read, raise_error: Callable[[int, int], None]) -> None:
        self._read = read
        self._raise_error = raise_error

    def register(self, hooks: NodeHooks) -> None:
        hooks.sync_length.append(self.on_sync)

    def on_sync(self, length: int) -> None:
        overflow = self._read(SYNC_COUNTER_OVERFLOW, 0) or 0
        if length != self.expected_length(overflow):
            self._raise_error(EmcyCode.SYNC_LENGTH, COMMUNICATION_ERROR_BIT)

    def expected_length(self, overflow: int) -> int | None:
        return 1 if overflow else 0


@breaks(SyncLengthCheck, "sync_length_error_silent")
class SyncLengthErrorSilent(SyncLengthCheck):
    """A SYNC of the wrong length records no error and sends no EMCY."""

    def on_sync(self, length: int) -> None:
        return


@breaks(SyncCobIdRules, "sync_generate_bit_accepted")
class SyncGenerateBitAccepted(SyncCobIdRules):
    def generate_accepted(self) -> bool:
        return True


@breaks(SyncCobIdRules, "sync_producer")
class SyncProducerVariant(SyncCobIdRules):
    """A variant, not a fault: the device can generate SYNC (1005h bit 30 accepted), as CANopenNode's demo can."""

    def generate_accepted(self) -> bool:
        return True


@breaks(SyncCobIdRules, "sync_restricted_can_id_accepted")
class SyncRestrictedCanIdAccepted(SyncCobIdRules):
    def can_id_accepted(self, can_id: int) -> bool:
        return True


@breaks(SyncConsumer, "sync_cob_id_ignored")
class SyncCobIdIgnored(SyncConsumer):
    def cob_id(self) -> int:
        return SYNC_COB_ID


@breaks(SyncLengthCheck, "sync_length_unchecked")
class SyncLengthUnchecked(SyncLengthCheck):
    def on_sync(self, length: int) -> None:
        pass
