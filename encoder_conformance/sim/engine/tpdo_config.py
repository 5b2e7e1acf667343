"""The configuration of one TPDO as the engine loaded it (shared by the engine and its add-ons)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class TpdoConfig:
    number: int  # 1-based
    cob_id: int
    valid: bool
    transmission_type: int
    inhibit_100us: int
    event_timer_ms: float  # effective timer period (0: no timer)
    mapping: list[tuple[int, int, int]]  # (index, sub, bits)
    sync_every: int = 0  # sent on every n-th SYNC (0: not SYNC-counted)
    on_change: bool = False  # sent when the payload changes
    acyclic_sync: bool = False  # type 0: sent on a SYNC after the payload changed
    rtr: bool = False  # answers a remote frame on its COB-ID
    rtr_allowed: bool = True  # sub 1 bit 30 clear
    sampled_at_sync: bool = False  # type 252: the payload is sampled at SYNC, sent on RTR
    sample: bytes = b""  # type 252: the payload of the last SYNC
    sync_start: int = 0  # sub 6 with 1019h > 0: the counter of the first SYNC counted (0: none)
    waiting_for_start: bool = False
    sync_count: int = 0
    sends_per_change: int = 1  # frames per detected change (send-repeat counter)
    repeats_left: int = 0  # frames of the last change still to send, one per change poll
    sync_limit: int = 0  # SYNC-driven frames in all until the payload changes (0: no limit)
    sync_sent: int = 0
    last_payload: bytes | None = None
    last_sent: float = field(default=-1e9)
    delayed: bool = False  # a transmission waits for the end of the inhibit time
