"""Non-volatile memory of a simulated node: a JSON file, so stored values survive a power cycle."""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path

Key = tuple[int, int]


def _encode_key(key: Key) -> str:
    return f"0x{key[0]:04X}.{key[1]}"


def _decode_key(text: str) -> Key:
    index, sub = text.split(".")
    return int(index, 16), int(sub)


class NonVolatileMemory:
    """Stored object values keyed by (index, sub). ``path=None`` keeps them in memory only."""

    def __init__(self, path: Path | None = None) -> None:
        self.path = path
        self._values: dict[Key, int | float | str] = {}
        #: told of every change ("stored" / "removed", the keys): the simulator's log
        self.listeners: list[Callable[[str, list[Key]], None]] = []
        if path is not None and path.exists():
            raw = json.loads(path.read_text(encoding="utf-8"))
            self._values = {_decode_key(k): v for k, v in raw.get("values", {}).items()}

    def get(self, key: Key) -> int | float | str | None:
        return self._values.get(key)

    def __contains__(self, key: Key) -> bool:
        return key in self._values

    def put_many(self, values: Mapping[Key, int | float | str]) -> None:
        self._values.update(values)
        self._flush()
        for listener in self.listeners:
            listener("stored", list(values))

    def remove_many(self, keys: list[Key]) -> None:
        for key in keys:
            self._values.pop(key, None)
        self._flush()
        for listener in self.listeners:
            listener("removed (back to defaults)", keys)

    def snapshot(self) -> dict[Key, int | float | str]:
        return dict(self._values)

    def _flush(self) -> None:
        if self.path is None:
            return
        payload = {"values": {_encode_key(k): v for k, v in sorted(self._values.items())}}
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=self.path.parent, prefix=".nvm-", suffix=".json")
        with os.fdopen(fd, "w", encoding="utf-8") as handle:  # atomic: write, then rename
            json.dump(payload, handle, indent=1)
        os.replace(tmp, self.path)
