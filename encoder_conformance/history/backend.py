"""Open the history wherever it lives: ``open_db(target)`` gives a Db on an SQLite file or a PostgreSQL URL.

psycopg is imported only for a PostgreSQL history, so an SQLite station (and the command line) starts as fast as
before.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from encoder_conformance.errors import HistoryError
from encoder_conformance.history import store_sqlite
from encoder_conformance.history.dbapi import Db
from encoder_conformance.history.target import PostgresUrl, Target


@contextmanager
def open_db(target: Target, create: bool = True, readonly: bool = False,
            busy_timeout_s: float = 10.0) -> Iterator[Db]:
    """A connection with the schema in place; every problem (unreachable, refused, newer schema, not a database)
    comes out as HistoryError. ``create``: an empty database gets the tables; ``readonly``: nothing is written,
    not even a schema upgrade."""
    if isinstance(target, PostgresUrl):
        try:
            from encoder_conformance.history import store_postgres
        except ImportError as exc:  # a dependency, but an installation may lack it
            raise HistoryError(f"{target}: the PostgreSQL driver is missing ({exc}); pip install "
                               "'psycopg[binary]'") from None
        with store_postgres.connect(target.url, create=create, readonly=readonly) as db:
            yield db
    else:
        with store_sqlite.connect(Path(target), create=create, readonly=readonly,
                                  busy_timeout_s=busy_timeout_s) as db:
            yield db


def upgrade(target: Target) -> tuple[int, int]:
    """``history upgrade``: bring the schema to this suite's version; (version found, version now)."""
    if isinstance(target, PostgresUrl):
        from encoder_conformance.history import store_postgres

        return store_postgres.upgrade_only(target.url)
    path = Path(target)
    found = store_sqlite.file_version(path)
    with store_sqlite.connect(path, create=False):
        pass
    return found, store_sqlite.file_version(path)
