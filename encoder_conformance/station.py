"""A station file: what a bench always uses (CAN adapter, node-id, power switch), so its operator
types only the profile. Command-line options override it. Strictly validated: an unknown or
ill-typed key is an error naming the file, the key and the fix.

```yaml
station: bench-3                 # a name for the report
can: {interface: pcan, channel: PCAN_USBBUS1, bitrate: 250000}
node_id: 5
power: {off_command: "relayctl 3 off", on_command: "relayctl 3 on", off_time_s: 1.0}   # or: power: manual
```
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class StationCan(_Strict):
    interface: str
    channel: str | None = None
    bitrate: int | None = Field(default=None, gt=0)


class StationPower(_Strict):
    """YAML reads bare ``on``/``off`` keys as booleans, hence the longer names."""

    off_command: str = Field(description="shell command that switches the device off (exit status 0 = done)")
    on_command: str = Field(description="shell command that switches the device on")
    off_time_s: float = Field(default=1.0, ge=0, le=60)


class Station(_Strict):
    station: str
    can: StationCan | None = None
    node_id: int | None = Field(default=None, ge=1, le=127)
    power: StationPower | Literal["manual"] | None = None


class StationError(Exception):
    """The station file is missing or invalid; the message names file, key and fix."""


def load_station(path: Path) -> Station:
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise StationError(f"--station {path}: cannot read it: {exc.strerror}") from None
    except yaml.YAMLError as exc:
        raise StationError(f"--station {path}: not valid YAML: {exc}") from None
    try:
        return Station.model_validate(raw)
    except ValidationError as exc:
        problems = [f"{path}: {'.'.join(str(p) for p in e['loc']) or '(top level)'}: {e['msg']}"
                    for e in exc.errors()]
        raise StationError("invalid station file:\n  " + "\n  ".join(problems)) from None
