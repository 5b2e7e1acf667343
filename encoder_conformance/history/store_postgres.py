"""The PostgreSQL history: one database for many goods-in stations (psycopg 3, imported only for such a URL).

psycopg 3 because it is PostgreSQL's maintained Python driver (``psycopg[binary]`` brings libpq, no compiler or
system library needed). Each call opens one connection in autocommit mode; a run's record is one transaction, so
a station killed half-way leaves nothing (the server rolls it back). Eight stations writing at once need no lock
of ours: every run is its own rows, and ``runs.run_key`` (UNIQUE) makes a re-sent record a no-op.

The schema version is the one row of ``schema_version``. A station that finds an older schema upgrades it in one
transaction under an advisory lock (the other stations wait for it, then find it done); where its database user
may not change the tables, the message names the command the database's owner runs. A newer schema is refused.
``readonly`` (the page): the session is read-only (``default_transaction_read_only``), any known version is read.
Connecting gives up after ``connect_timeout`` (5 s) and a statement after ``statement_timeout`` (15 s) unless the
URL says otherwise, so an unreachable server holds a run only that long before its record goes to the spool.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager, suppress
from typing import Any

import psycopg
from psycopg.conninfo import conninfo_to_dict
from psycopg.rows import dict_row

from encoder_conformance.errors import HistoryError
from encoder_conformance.history.dbapi import Db
from encoder_conformance.history.schema import SCHEMA_VERSION, newer_message, steps
from encoder_conformance.history.target import PostgresUrl

CONNECT_TIMEOUT_S = 5
STATEMENT_TIMEOUT_MS = 15_000
UPGRADE_LOCK = 40630129  # pg_advisory_lock key: one upgrader at a time


class PostgresDb(Db):
    dialect = "postgresql"

    def _sql(self, sql: str) -> str:
        return sql.replace("?", "%s")

    def many(self, sql: str, params: Iterable[Sequence[Any]]) -> None:
        with self.connection.cursor() as cursor:
            cursor.executemany(self._sql(sql), list(params))

    @contextmanager
    def transaction(self) -> Iterator[None]:
        with self.connection.transaction():
            yield

    @property
    def in_run_order(self) -> str:
        return "seq"


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _options(url: str, readonly: bool) -> dict[str, Any]:
    try:
        given = conninfo_to_dict(url)
    except psycopg.ProgrammingError as exc:
        raise HistoryError(f"{PostgresUrl(url)}: not a PostgreSQL URL ({_one_line(exc)}); give "
                           "postgresql://user@host[:port]/database") from None
    options: dict[str, Any] = {"connect_timeout": CONNECT_TIMEOUT_S, "application_name": "encoder-conformance"}
    options.update({k: v for k, v in given.items() if k in ("connect_timeout", "application_name")})
    settings = [f"-c statement_timeout={STATEMENT_TIMEOUT_MS}"] if "statement_timeout" not in url else []
    if readonly:
        settings.append("-c default_transaction_read_only=on")
    if settings:
        options["options"] = " ".join([str(given.get("options") or ""), *settings]).strip()
    return options


@contextmanager
def _opened(url: str, readonly: bool) -> Iterator[tuple[PostgresDb, int]]:
    """A connection and the schema version it holds (a newer one refused); psycopg problems as HistoryError."""
    where = str(PostgresUrl(url))
    try:
        with psycopg.connect(url, autocommit=True, row_factory=dict_row, **_options(url, readonly)) as connection:
            db = PostgresDb(connection, where)
            version = _version(db)
            if version > SCHEMA_VERSION:
                raise HistoryError(newer_message(where, version))
            yield db, version
    except psycopg.Error as exc:
        raise HistoryError(f"{where}: {_one_line(exc)}") from exc


@contextmanager
def connect(url: str, create: bool = True, readonly: bool = False) -> Iterator[Db]:
    """A connection with the current schema in place (``create``: made where the database has none yet;
    ``readonly``: any known version, nothing written); every psycopg problem comes out as HistoryError."""
    with _opened(url, readonly) as (db, version):
        if version == 0 and not create:
            raise HistoryError(f"{db.where}: no history in this database yet (no run recorded into it)")
        if version < SCHEMA_VERSION and not readonly:
            _upgrade(db)
        yield db


def _version(db: Db) -> int:
    if db.value("SELECT to_regclass('schema_version') IS NOT NULL AS present") is not True:
        return 0
    return int(db.value("SELECT max(version) FROM schema_version") or 0)


def _upgrade(db: Db) -> None:
    try:
        # a session lock, taken outside the transaction: the version is read after it in a new transaction, which
        # sees the tables a previous holder made (a transaction keeps the catalogue it started with)
        db.run("SELECT pg_advisory_lock(?)", (UPGRADE_LOCK,))
        try:
            version = _version(db)
            if version > SCHEMA_VERSION:
                raise HistoryError(newer_message(db.where, version))
            if version < SCHEMA_VERSION:
                with db.transaction():
                    for step in steps("postgresql")[version:]:
                        for statement in step:
                            db.run(statement)
                    db.run("DELETE FROM schema_version")
                    db.run("INSERT INTO schema_version (version) VALUES (?)", (SCHEMA_VERSION,))
        finally:
            with suppress(psycopg.Error):
                db.run("SELECT pg_advisory_unlock(?)", (UPGRADE_LOCK,))
    except psycopg.errors.InsufficientPrivilege as exc:
        user = db.connection.info.user
        raise HistoryError(
            f"{db.where}: the history's schema is older than this suite's ({SCHEMA_VERSION}) and user {user!r} may "
            f"not change it ({_one_line(exc)}); have the database's owner run: encoder-conformance history "
            "upgrade --db postgresql://OWNER@HOST/DATABASE") from None


def upgrade_only(url: str) -> tuple[int, int]:
    """``history upgrade``: (version found, version now)."""
    with _opened(url, readonly=False) as (db, found):
        if found < SCHEMA_VERSION:
            _upgrade(db)
        return found, _version(db)
