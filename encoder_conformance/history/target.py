"""Where the history lives: an SQLite file (the embedded default, no set-up) or a PostgreSQL URL (one history
for many goods-in stations), from ``--history``, the station file's ``history``, $ENCODER_CONFORMANCE_HISTORY or
reports/history.sqlite.

A URL is shown without its password wherever it is printed or stored (messages, the spool); put the password in
``~/.pgpass`` or $PGPASSWORD instead of the URL, as libpq allows.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import urlsplit, urlunsplit

from encoder_conformance.errors import HistoryError
from encoder_conformance.paths import default_reports_dir

ENV_VAR = "ENCODER_CONFORMANCE_HISTORY"
DEFAULT_PATH = default_reports_dir() / "history.sqlite"
POSTGRES_SCHEMES = ("postgresql", "postgres")
_SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9+.-]*)://")
_PASSWORD_PARAMETER = re.compile(r"(?i)([?&]password=)[^&]*")


@dataclass(frozen=True)
class PostgresUrl:
    """A PostgreSQL history (libpq URL); ``str()`` gives it without a password."""

    url: str

    def __str__(self) -> str:
        return shown(self.url)


#: an SQLite file or a PostgreSQL database
Target = Path | PostgresUrl


def shown(url: str) -> str:
    """The URL without its password (for messages and the spool)."""
    parts = urlsplit(url)
    netloc = parts.netloc
    if "@" in netloc:
        user, _, host = netloc.rpartition("@")
        if ":" in user:
            netloc = f"{user.partition(':')[0]}:***@{host}"
    return _PASSWORD_PARAMETER.sub(r"\1***", urlunsplit(parts._replace(netloc=netloc)))


def parse_target(text: str | os.PathLike[str]) -> Target:
    """A path, or a postgresql:// URL; another URL scheme is refused (HistoryError)."""
    value = os.fspath(text)
    scheme = _SCHEME.match(value)
    if scheme is None:
        return Path(value)
    if scheme.group(1).lower() in POSTGRES_SCHEMES:
        return PostgresUrl(value)
    raise HistoryError(f"{shown(value)}: a history is an SQLite file path or a postgresql://user@host/database "
                       "URL")


def history_path(given: str | os.PathLike[str] | None = None,
                 station_history: str | os.PathLike[str] | None = None) -> Target:
    """Where the history lives: the option, else the station file's ``history``, else the environment's
    ENCODER_CONFORMANCE_HISTORY, else reports/history.sqlite in the repository."""
    if given:
        return parse_target(given)
    if station_history is not None:
        return parse_target(station_history)
    if os.environ.get(ENV_VAR):
        return parse_target(os.environ[ENV_VAR])
    return DEFAULT_PATH


def target_key(target: Target) -> str:
    """The target as the spool names it: the absolute file, or the URL without its password."""
    return str(target) if isinstance(target, PostgresUrl) else str(Path(target).absolute())
