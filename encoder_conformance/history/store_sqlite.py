"""The SQLite history: one file, the embedded default (the standard library's sqlite3, no server to run).

Two runs at a time (parallel stations, ``repeat``) are safe with SQLite's locking: the database is opened in WAL
mode with a generous busy timeout, so a writer waits for the other instead of failing, and readers (``history
list``, the page) never block a run. ``PRAGMA user_version`` holds the schema version: an older file is upgraded
by the first connection that may write, in one transaction; a file written by a newer version is refused with a
message instead of being misread. The page opens the file read-only (``mode=ro``, ``query_only``).
"""

from __future__ import annotations

import sqlite3
from collections.abc import Iterable, Iterator, Sequence
from contextlib import closing, contextmanager, suppress
from pathlib import Path
from typing import Any

from encoder_conformance.errors import HistoryError
from encoder_conformance.history.dbapi import Db, Row
from encoder_conformance.history.schema import SCHEMA_VERSION, newer_message, steps


def _dict_row(cursor: sqlite3.Cursor, values: tuple[Any, ...]) -> Row:
    return {column[0]: value for column, value in zip(cursor.description, values, strict=True)}


class SqliteDb(Db):
    dialect = "sqlite"

    def many(self, sql: str, params: Iterable[Sequence[Any]]) -> None:
        self.connection.executemany(sql, params)

    @contextmanager
    def transaction(self) -> Iterator[None]:
        self.connection.execute("BEGIN IMMEDIATE")  # the write lock now: a parallel writer waits, never fails
        try:
            yield
        except BaseException:
            with suppress(sqlite3.Error):
                self.connection.execute("ROLLBACK")
            raise
        self.connection.execute("COMMIT")

    @property
    def in_run_order(self) -> str:
        return "rowid"


@contextmanager
def connect(path: Path, create: bool = True, readonly: bool = False, busy_timeout_s: float = 10.0) -> Iterator[Db]:
    """A connection with the current schema in place (``readonly``: any known version, nothing written); every
    sqlite3 problem comes out as HistoryError."""
    if not create and not path.is_file():
        raise HistoryError(f"{path}: no history database there")
    try:
        if create:
            path.parent.mkdir(parents=True, exist_ok=True)
        if readonly:
            raw = sqlite3.connect(f"{path.absolute().as_uri()}?mode=ro", uri=True, timeout=busy_timeout_s,
                                  isolation_level=None, check_same_thread=False)
        else:
            raw = sqlite3.connect(path, timeout=busy_timeout_s, isolation_level=None)
        with closing(raw) as connection:
            connection.row_factory = _dict_row
            db = SqliteDb(connection, str(path))
            if readonly:
                connection.execute("PRAGMA query_only = ON")
                _known_version(db)
            else:
                connection.execute("PRAGMA foreign_keys = ON")
                _prepare(db)
            yield db
    except (sqlite3.Error, OSError) as exc:
        raise HistoryError(f"{path}: {exc}") from exc


def _version(db: Db) -> int:
    return int(db.value("PRAGMA user_version"))


def _known_version(db: Db) -> int:
    version = _version(db)
    if version > SCHEMA_VERSION:
        raise HistoryError(newer_message(db.where, version))
    if version == 0:
        raise HistoryError(f"{db.where}: no history in this file yet (no run recorded into it)")
    return version


def _prepare(db: Db) -> None:
    version = _version(db)
    if version > SCHEMA_VERSION:
        raise HistoryError(newer_message(db.where, version))
    if version < SCHEMA_VERSION:
        with db.transaction():  # a second process upgrading at the same moment waits, then finds it done
            version = _version(db)
            for step in steps("sqlite")[version:]:
                for statement in step:
                    db.run(statement)
            db.run(f"PRAGMA user_version = {SCHEMA_VERSION}")
    if db.value("PRAGMA journal_mode") != "wal":
        # WAL: readers (history list) never block a run's write. Best effort: switching needs the database to
        # itself and SQLite does not wait for that (seen: two runs creating it at once); the rollback journal
        # with the busy timeout is just as safe, and a later connection switches.
        with suppress(sqlite3.OperationalError):
            db.run("PRAGMA journal_mode = WAL")


def file_version(path: Path) -> int:
    """The schema version of an existing file, read without changing it."""
    with connect(path, create=False, readonly=True) as db:
        return _version(db)
