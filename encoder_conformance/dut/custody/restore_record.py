"""What a device's give-back found, did and could not do: ``device-restore.json`` (``custody.give_back`` fills it)."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path


@dataclass
class Change:
    """An entry that differs from the snapshot."""

    label: str
    expected: str | None
    observed: str | None

    def describe(self) -> str:
        return f"{self.label} = {self.observed or 'unreadable'} instead of {self.expected}"


@dataclass
class RestoreRecord:
    """What the give-back found, did and could not do (shown in the report, kept as JSON)."""

    snapshot: str | None
    left_changed: list[Change] = field(default_factory=list)  # values in use at the end of the run
    stored_changed: list[Change] = field(default_factory=list)  # stored values after a reset
    written: list[str] = field(default_factory=list)
    store_commands: list[str] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)
    run_store_commands: dict[str, int] = field(default_factory=dict)  # what the tests sent (EEPROM wear)
    restore_store_commands: int = 0
    memory: str | None = None  # the memory is not as found where the values are (``boot_memory``)
    seconds: float = 0.0
    done: bool = False

    @property
    def ok(self) -> bool:
        return self.done and not self.failures

    def fail(self, text: str) -> None:
        self.failures.append(text)

    def save(self, path: Path) -> None:
        path.write_text(json.dumps(asdict(self), indent=1), encoding="utf-8")
