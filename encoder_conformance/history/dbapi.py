"""One open history database, SQLite or PostgreSQL, behind the few calls the history makes.

The SQL is written once, with ``?`` placeholders and the constructs both speak (``INSERT ... ON CONFLICT ...
RETURNING``, ``LIMIT ... OFFSET``, ``CASE``); rows come back as plain dicts. No SQLAlchemy: four tables and a
dozen statements need no query builder, and its import (about 0.2 s) would lengthen every acceptance run.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from contextlib import AbstractContextManager
from typing import Any

Row = dict[str, Any]


class Db:
    """A connection in autocommit mode; ``transaction()`` groups writes. Driver errors surface as HistoryError
    from the connecting context manager (store_sqlite.connect, store_postgres.connect)."""

    dialect = ""

    def __init__(self, connection: Any, where: str) -> None:
        self.connection = connection
        self.where = where  # the file or the URL without password, for messages

    def _sql(self, sql: str) -> str:
        return sql

    def rows(self, sql: str, params: Sequence[Any] = ()) -> list[Row]:
        return list(self.connection.execute(self._sql(sql), params).fetchall())

    def one(self, sql: str, params: Sequence[Any] = ()) -> Row | None:
        return self.connection.execute(self._sql(sql), params).fetchone()

    def value(self, sql: str, params: Sequence[Any] = ()) -> Any:
        row = self.one(sql, params)
        return None if row is None else next(iter(row.values()))

    def run(self, sql: str, params: Sequence[Any] = ()) -> None:
        self.connection.execute(self._sql(sql), params)

    def many(self, sql: str, params: Iterable[Sequence[Any]]) -> None:
        raise NotImplementedError

    def transaction(self) -> AbstractContextManager[None]:
        """A write transaction that holds the write lock from its start (SQLite: BEGIN IMMEDIATE)."""
        raise NotImplementedError

    @property
    def in_run_order(self) -> str:
        """ORDER BY of a run's areas and results: as recorded."""
        raise NotImplementedError
