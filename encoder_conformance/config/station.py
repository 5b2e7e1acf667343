"""A station file: what a bench always uses (CAN adapter, node-id, power switch, operator, where reports
and the history go), so its operator types only the profile. Command-line options override it; python-can's
own configuration (CAN_INTERFACE, ~/can.conf) fills what neither gives. Strictly validated: an unknown or
ill-typed key is an error naming the file, the key and the fix. TOML (``.toml``) or YAML (any other name):

```toml
station = "goods-in-2"            # a name for the report, the certificate and the history
operator = "J. Meyer"
node_id = 5
shaft_drive = "bench_motor:connect=/dev/ttyUSB0"   # optional motor plug-in (see --shaft-drive)
reports = "/srv/conformance/reports"               # report folders go here (default reports/)
history = "/srv/conformance/history.sqlite"        # the history: an SQLite file (default reports/history.sqlite)
                                                   # or postgresql://user@host/db, shared by many stations

[can]
interface = "pcan"
channel = "PCAN_USBBUS1"
bitrate = 250000

[power]                           # or: power = "manual" (the operator is asked and Enter continues)
off_command = "relayctl 3 off"
on_command = "relayctl 3 on"
off_time_s = 1.0
```

Relative paths (reports, history) are taken from the station file's folder.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from encoder_conformance.errors import StationError


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
    operator: str | None = None
    can: StationCan | None = None
    node_id: int | None = Field(default=None, ge=1, le=127)
    power: StationPower | Literal["manual"] | None = None
    shaft_drive: str | None = Field(default=None, description="motor plug-in MODULE:FACTORY[=ARGUMENT]")
    reports: Path | None = Field(default=None, description="folder the report folders go into")
    history: str | None = Field(default=None, description="the history database: an SQLite file, or a PostgreSQL "
                                "URL (postgresql://user@host/database) that many stations share")

    def resolved(self, folder: Path) -> Station:
        """Relative paths taken from the station file's folder (a URL stays as it is)."""
        updates: dict[str, object] = {}
        if self.reports is not None and not self.reports.is_absolute():
            updates["reports"] = folder / self.reports
        if self.history is not None and "://" not in self.history and not Path(self.history).is_absolute():
            updates["history"] = str(folder / self.history)
        return self.model_copy(update=updates)


def _parse(path: Path) -> Any:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise StationError(f"--station {path}: cannot read it: {exc.strerror}; give the path of the station "
                           "file (TOML or YAML)") from None
    if path.suffix == ".toml":
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise StationError(f"--station {path}: not valid TOML: {exc}") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise StationError(f"--station {path}: not valid YAML: {exc}") from None


def load_station(path: Path) -> Station:
    raw = _parse(path)
    try:
        return Station.model_validate(raw).resolved(path.resolve().parent)
    except ValidationError as exc:
        problems = [f"{path}: {'.'.join(str(p) for p in e['loc']) or '(top level)'}: {e['msg']}"
                    for e in exc.errors()]
        raise StationError("invalid station file:\n  " + "\n  ".join(problems)) from None
