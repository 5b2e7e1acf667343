"""What the probe saw, kept apart from what it concludes (``apply.py`` turns it into draft changes)."""

from __future__ import annotations

from dataclasses import dataclass, field

from encoder_conformance.probe.link import Answer

Key = tuple[int, int]


@dataclass
class TpdoTypes:
    """18xxh sub 2 written with every value 0..255 on one TPDO."""

    communication_index: int
    accepted: list[int]
    refused: dict[int, list[int]]  # abort code (0: no answer) -> the types refused with it
    frames: dict[int, str] = field(default_factory=dict)  # type -> 'download 1800h.02 F1 -> accepted'


@dataclass
class Findings:
    readings: dict[Key, list[Answer]] = field(default_factory=dict)  # each entry's reads, oldest first
    reset: bool = False  # the device was reset and answered again
    boot_up_ms: float | None = None
    nmt_state_found: int | None = None  # from a heartbeat before the probe changed anything
    tpdo_types: TpdoTypes | None = None
    #: situation -> (CiA code, answer, the frames: request -> answer)
    aborts: dict[str, tuple[int, Answer, str]] = field(default_factory=dict)
    lss: list[str] | None = None  # the services answered (None: LSS not probed)
    block_sdo: bool | None = None
    segmented_sdo: bool | None = None
    sync_producer: bool | None = None
    node_guarding: bool | None = None
    store_subindices: list[int] | None = None
    restore_subindices: list[int] | None = None
    notes: list[str] = field(default_factory=list)  # what stays open: numbered todos in the draft
    put_back_failures: list[str] = field(default_factory=list)

    def value(self, key: Key) -> bytes | None:
        """The first value read of an entry (None: not read or not readable)."""
        reads = self.readings.get(key, [])
        return reads[0].data if reads else None
