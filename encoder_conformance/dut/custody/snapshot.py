"""The device as the run found it: every configurable value, and what the device has stored.

Before the first test the run reads every readable-and-writable entry the profile declares
(``found``: the values in use, possibly changed without storing), resets the node and reads them
again (``stored``: what the device loads from its memory); for an encoder with a preset, its
reference point both times instead of the preset objects, which are no values to write back
(``reference_point``). The snapshot is written as JSON into the report directory before any test
runs, so ``encoder-conformance restore --from`` can put the device back even after a crash or a
power loss of the test PC.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.dut.bench.reference_point import ReferencePoint, preset_keys
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.sdo.patient_read import read_patiently
from encoder_conformance.dut.store.store_watch import store_command_objects
from encoder_conformance.profile.schema import DeviceProfile, EntrySpec

SNAPSHOT_FILE = "device-snapshot.json"
FORMAT = "encoder-conformance device snapshot 1"

Key = tuple[int, int]


def custody_keys(profile: DeviceProfile) -> list[Key]:
    """Entries a run must give back: readable, writable configuration (no commands, nothing that changes by itself,
    no preset object: its reference point is given back instead)."""
    commands = store_command_objects(profile)
    presets = preset_keys(profile)
    return [
        (index, sub)
        for index, sub, _, entry in profile.iter_entries()
        if _is_configuration(entry) and index not in commands and (index, sub) not in presets
    ]


def _is_configuration(entry: EntrySpec) -> bool:
    return entry.readable and entry.writable and not entry.dynamic


def is_stored(entry: EntrySpec | None) -> bool:
    """Entries whose value survives a reset when stored (the profile's persisted_by)."""
    return entry is not None and entry.persisted_by not in ("none", "volatile")


@dataclass
class SnapshotEntry:
    index: int
    sub: int
    name: str
    persisted_by: str
    found: str | None  # hex of the value in use before the run (None: unreadable before the reset)
    stored: str | None  # hex of the value after reset node (what the device loads); None: unreadable

    @property
    def key(self) -> Key:
        return self.index, self.sub

    @property
    def label(self) -> str:
        return f"{self.index:04X}h.{self.sub:02X} {self.name}"

    def target_found(self) -> bytes | None:
        """The value to put back at the end of the run."""
        value = self.found if self.found is not None else self.stored
        return None if value is None else bytes.fromhex(value)

    def target_stored(self) -> bytes | None:
        return None if self.stored is None else bytes.fromhex(self.stored)


@dataclass
class Snapshot:
    """What a run must give back, as a file a later ``restore --from`` can read."""

    profile_id: str
    profile_sha256: str
    node_id: int
    identity: dict[str, str]
    found_readable: bool  # the device answered SDO before the run's first reset
    found_state: int | None  # NMT state seen in a heartbeat before the run touched the device
    entries: list[SnapshotEntry] = field(default_factory=list)
    #: the reference point (6509h or the position at rest) before the run and after the reset; None where the
    #: device has no preset, or in a snapshot from before the reference point was recorded
    reference_found: ReferencePoint | None = None
    reference_stored: ReferencePoint | None = None
    #: node-IDs an LSS test gave the device (255: unconfigured) and has not put back yet: where a later
    #: ``restore --from`` looks for it (absent in snapshots of older runs)
    lss_node_ids: list[int] = field(default_factory=list)
    #: EMCY codes the node sent after the boot-up that showed what it stored (5000h: no valid stored data)
    boot_emcy: list[int] = field(default_factory=list)
    taken_at: str = field(default_factory=lambda: time.strftime("%Y-%m-%dT%H:%M:%S%z"))
    format: str = FORMAT

    @property
    def serial(self) -> str | None:
        return self.identity.get("serial number (1018h.4)")

    @property
    def reference_in_use(self) -> ReferencePoint | None:
        """The reference point to give back at the end (the stored one where none was readable before)."""
        return self.reference_found or self.reference_stored

    def entry(self, key: Key) -> SnapshotEntry | None:
        return next((e for e in self.entries if e.key == key), None)

    def save(self, path: Path) -> Path:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(asdict(self), indent=1), encoding="utf-8")
        tmp.replace(path)  # atomic: a crash never leaves half a snapshot
        return path

    @classmethod
    def load(cls, path: Path) -> Snapshot:
        """Read a snapshot file; ValueError names the file and what is wrong."""
        try:
            raw = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ValueError(f"{path}: cannot read the snapshot: {exc}") from None
        if not isinstance(raw, dict) or raw.get("format") != FORMAT:
            raise ValueError(f"{path}: not a device snapshot (expected format {FORMAT!r})")
        try:
            entries = [SnapshotEntry(**e) for e in raw.pop("entries")]
            # the reference points are absent in snapshots of older runs
            found = ReferencePoint.from_dict(raw.pop("reference_found", None))
            stored = ReferencePoint.from_dict(raw.pop("reference_stored", None))
            return cls(entries=entries, reference_found=found, reference_stored=stored, **raw)
        except (TypeError, KeyError) as exc:
            raise ValueError(f"{path}: malformed snapshot: {exc}") from None


def read_values(dut: DeviceLink, keys: list[Key]) -> dict[Key, bytes | None]:
    """Each entry's value (None where the device refuses the read).

    A read that timed out while the device still answers is asked once more: custody needs the value, and a
    late answer on a loaded tester host is no verdict on the device (the timing suites judge its answer times).
    """
    values: dict[Key, bytes | None] = {}
    for index, sub in keys:
        try:
            values[(index, sub)] = read_patiently(dut, index, sub)
        except SdoAbortedError:
            values[(index, sub)] = None
    return values


def hex_or_none(data: bytes | None) -> str | None:
    return None if data is None else data.hex()
