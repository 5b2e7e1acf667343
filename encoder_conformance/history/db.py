"""The run history: one row per run, its areas and every test's outcome, in an SQLite file or a PostgreSQL
database (the same schema and the same calls on both).

SQLite (the standard library's sqlite3) is the embedded default because a goods-in station is often one PC: no
server to run, one file to back up (store_sqlite.py). Many stations share one history in PostgreSQL
(store_postgres.py): give ``--history postgresql://user@host/db``. Where the history is: target.py; the tables
and their versions: schema.py; one run in: records.py; a run that could not be recorded waits in the spool
(spool.py, sync.py).

This module is what the rest of the suite calls: ``record_run``, ``list_runs``, ``get_run``, ``load_runs``,
``note_certificate``, ``history_path``.
"""

from __future__ import annotations

import json
import uuid
from dataclasses import dataclass
from pathlib import Path

from encoder_conformance.errors import HistoryError
from encoder_conformance.history import records
from encoder_conformance.history.backend import open_db
from encoder_conformance.history.dbapi import Db, Row
from encoder_conformance.history.schema import SCHEMA_VERSION
from encoder_conformance.history.target import DEFAULT_PATH, ENV_VAR, PostgresUrl, Target, history_path
from encoder_conformance.run_summary import RunSummary, TestResult

__all__ = ["DEFAULT_PATH", "ENV_VAR", "OFF", "SCHEMA_VERSION", "Filters", "HistoryError", "PostgresUrl",
           "StoredRun", "Target", "get_run", "history_path", "list_runs", "load_runs", "note_certificate",
           "record_new", "record_run"]

BUSY_TIMEOUT_S = 10.0  # SQLite: a parallel run's write takes milliseconds; this only bounds a stuck writer
OFF = "off"  # --history off: this run is not recorded (the fault matrix's throw-away runs)
_AREA_COLUMNS = "run_id, area, passed, failed, warnings, skipped, verdict"
_RESULT_COLUMNS = "run_id, nodeid, area, outcome, basis, source, message, duration_s"


def record_new(summary: RunSummary, target: Target, key: str | None = None,
               certificate: Path | str | None = None) -> tuple[int, bool]:
    """Record one run (its areas and results) under its key: (id, True), or (id, False) where a record with that
    key is there already. Raises HistoryError."""
    with open_db(target, busy_timeout_s=BUSY_TIMEOUT_S) as db:
        return records.insert_run(db, summary, key or str(uuid.uuid4()),
                                  None if certificate is None else str(certificate))


def record_run(summary: RunSummary, db_path: Target, key: str | None = None,
               certificate: Path | str | None = None) -> int:
    """Append one run (its areas and results) and return its id. Raises HistoryError."""
    return record_new(summary, db_path, key, certificate)[0]


def note_certificate(db_path: Target, run_id: int, certificate: Path) -> None:
    with open_db(db_path, busy_timeout_s=BUSY_TIMEOUT_S) as db:
        records.note_certificate(db, run_id, str(certificate))


@dataclass(frozen=True)
class Filters:
    """What ``history list`` and ``export`` select; None selects everything."""

    serial: str | None = None
    since_utc: str | None = None  # ISO 8601 in UTC
    profile: str | None = None
    kind: str | None = None


def _where(filters: Filters) -> tuple[str, list[str]]:
    clauses, values = [], []
    for column, value in (("serial", filters.serial), ("profile_id", filters.profile), ("kind", filters.kind)):
        if value is not None:
            clauses.append(f"{column} = ?")
            values.append(value)
    if filters.since_utc is not None:
        clauses.append("started_utc >= ?")
        values.append(filters.since_utc)
    return (f"WHERE {' AND '.join(clauses)}" if clauses else ""), values


def list_runs(db_path: Target, filters: Filters = Filters()) -> list[Row]:
    """The runs matching ``filters``, oldest first."""
    where, values = _where(filters)
    with open_db(db_path, create=False, busy_timeout_s=BUSY_TIMEOUT_S) as db:
        return db.rows(f"SELECT * FROM runs {where} ORDER BY started_utc, id", values)


@dataclass
class StoredRun:
    """One run as the history holds it."""

    run: Row
    areas: list[Row]
    results: list[Row]

    def summary(self) -> RunSummary:
        """The run as a RunSummary again (for a certificate of a run whose report folder is gone)."""
        run = self.run
        results = [TestResult(r["nodeid"], r["area"], r["outcome"], r["basis"], r["source"], r["message"],
                              r["duration_s"] or 0.0) for r in self.results]
        restored = None if run["device_restored"] is None else bool(run["device_restored"])
        return RunSummary(kind=run["kind"], started=run["started"], profile_id=run["profile_id"],
                          profile_sha256=run["profile_sha256"], duration_s=run["duration_s"] or 0.0,
                          identity=json.loads(run["identity"]), settings=json.loads(run["settings"]),
                          station=run["station"], operator=run["operator"], results=results,
                          exit_code=run["exit_code"], could_not_test=run["could_not_test"],
                          device_restored=restored, report_dir=run["report_dir"])


def stored(db: Db, run: Row) -> StoredRun:
    """``run`` with its areas and results, in the order they were recorded."""
    order = db.in_run_order
    areas = db.rows(f"SELECT {_AREA_COLUMNS} FROM areas WHERE run_id = ? ORDER BY {order}", (run["id"],))
    results = db.rows(f"SELECT {_RESULT_COLUMNS} FROM results WHERE run_id = ? ORDER BY {order}", (run["id"],))
    return StoredRun(run, areas, results)


def get_run(db_path: Target, run_id: int) -> StoredRun | None:
    with open_db(db_path, create=False, busy_timeout_s=BUSY_TIMEOUT_S) as db:
        run = db.one("SELECT * FROM runs WHERE id = ?", (run_id,))
        return None if run is None else stored(db, run)


def load_runs(db_path: Target, filters: Filters = Filters()) -> list[StoredRun]:
    """The runs matching ``filters`` in full (areas and results), oldest first."""
    where, values = _where(filters)
    with open_db(db_path, create=False, busy_timeout_s=BUSY_TIMEOUT_S) as db:
        return [stored(db, run) for run in db.rows(f"SELECT * FROM runs {where} ORDER BY started_utc, id", values)]


def path_exists(target: Target) -> bool:
    """An SQLite file is there (a PostgreSQL database is asked when it is opened)."""
    return isinstance(target, PostgresUrl) or Path(target).is_file()
