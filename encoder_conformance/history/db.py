"""The local run history: one SQLite file, one row per run, its areas and every test's outcome.

SQLite (the standard library's sqlite3) because a goods-in station is one PC: no server to run, one file
to back up, and two runs at a time (parallel stations, ``repeat``) are safe with its locking. The database
is opened in WAL mode with a generous busy timeout, so a writer waits for the other instead of failing,
and readers (``history list``) never block a run. ``PRAGMA user_version`` holds the schema version: a
database written by a newer version is refused with a message instead of being misread.
"""

from __future__ import annotations

import json
import os
import sqlite3
from collections.abc import Iterator
from contextlib import closing, contextmanager, suppress
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from encoder_conformance.errors import HistoryError
from encoder_conformance.paths import default_reports_dir
from encoder_conformance.run_summary import RunSummary, TestResult

SCHEMA_VERSION = 1
ENV_VAR = "ENCODER_CONFORMANCE_HISTORY"
DEFAULT_PATH = default_reports_dir() / "history.sqlite"
BUSY_TIMEOUT_S = 10.0  # a parallel run's write takes milliseconds; this only bounds a stuck writer
OFF = "off"  # --history off: this run is not recorded (the fault matrix's throw-away runs)

_SCHEMA = """
CREATE TABLE IF NOT EXISTS runs (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    kind TEXT NOT NULL,               -- run | accept
    started TEXT NOT NULL,            -- ISO 8601 local time with offset, as the run saw it
    started_utc TEXT NOT NULL,        -- the same in UTC, for --since
    duration_s REAL,
    profile_id TEXT NOT NULL,
    profile_sha256 TEXT NOT NULL,
    serial TEXT,
    revision TEXT,
    vendor_id TEXT,
    product_code TEXT,
    device_name TEXT,
    overall TEXT NOT NULL,            -- PASS | FAIL | PASS WITH WARNINGS | COULD NOT TEST | NOT RUN
    could_not_test TEXT,
    station TEXT,
    operator TEXT,
    report_dir TEXT,
    exit_code INTEGER,
    device_restored INTEGER,          -- 1, 0, or NULL when the run changed nothing to restore
    identity TEXT NOT NULL,           -- JSON: what the device reported
    settings TEXT NOT NULL,           -- JSON: bus settings with their sources
    certificate TEXT                  -- the certificate's path, once one was written
);
CREATE INDEX IF NOT EXISTS runs_serial ON runs(serial);
CREATE INDEX IF NOT EXISTS runs_started ON runs(started_utc);
CREATE TABLE IF NOT EXISTS areas (
    run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
    area TEXT NOT NULL,
    passed INTEGER NOT NULL, failed INTEGER NOT NULL, warnings INTEGER NOT NULL, skipped INTEGER NOT NULL,
    verdict TEXT NOT NULL,
    PRIMARY KEY (run_id, area)
);
CREATE TABLE IF NOT EXISTS results (
    run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
    nodeid TEXT NOT NULL,
    area TEXT NOT NULL,
    outcome TEXT NOT NULL,
    basis TEXT,
    source TEXT,
    message TEXT NOT NULL,
    duration_s REAL,
    PRIMARY KEY (run_id, nodeid)
);
"""


def history_path(given: str | os.PathLike[str] | None = None, station_history: Path | None = None) -> Path:
    """Where the history lives: the option, else the station file's ``history``, else the environment's
    ENCODER_CONFORMANCE_HISTORY, else reports/history.sqlite in the repository."""
    if given:
        return Path(given)
    if station_history is not None:
        return Path(station_history)
    if os.environ.get(ENV_VAR):
        return Path(os.environ[ENV_VAR])
    return DEFAULT_PATH


def _utc(started: str) -> str:
    moment = datetime.fromisoformat(started)
    return (moment if moment.tzinfo else moment.astimezone()).astimezone(UTC).isoformat(timespec="seconds")


@contextmanager
def connect(path: Path, create: bool = True) -> Iterator[sqlite3.Connection]:
    """A connection with the schema in place; every sqlite3 problem comes out as HistoryError."""
    if not create and not path.is_file():
        raise HistoryError(f"{path}: no history database there")
    try:
        if create:
            path.parent.mkdir(parents=True, exist_ok=True)
        with closing(sqlite3.connect(path, timeout=BUSY_TIMEOUT_S)) as db:
            db.row_factory = sqlite3.Row
            db.execute("PRAGMA foreign_keys = ON")
            _prepare(db, path)
            yield db
    except (sqlite3.Error, OSError) as exc:
        raise HistoryError(f"{path}: {exc}") from exc


def _prepare(db: sqlite3.Connection, path: Path) -> None:
    version = db.execute("PRAGMA user_version").fetchone()[0]
    if version > SCHEMA_VERSION:
        raise HistoryError(f"{path}: written by a newer version of the suite (schema {version}, this one knows "
                           f"{SCHEMA_VERSION}); update the suite or use another --history file")
    if version < SCHEMA_VERSION:
        with db:  # one transaction: a second process creating the schema at the same moment waits, then sees it
            db.execute("BEGIN IMMEDIATE")
            for statement in _SCHEMA.split(";"):
                if statement.strip():
                    db.execute(statement)
            db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
    if db.execute("PRAGMA journal_mode").fetchone()[0] != "wal":
        # WAL: readers (history list) never block a run's write. Best effort: switching needs the database to
        # itself and SQLite does not wait for that (seen: two runs creating it at once); the rollback journal
        # with the busy timeout is just as safe, and a later connection switches.
        with suppress(sqlite3.OperationalError):
            db.execute("PRAGMA journal_mode = WAL")


def record_run(summary: RunSummary, db_path: Path) -> int:
    """Append one run (its areas and results) and return its id. Raises HistoryError."""
    identity = summary.identity
    row = {
        "kind": summary.kind, "started": summary.started, "started_utc": _utc(summary.started),
        "duration_s": summary.duration_s, "profile_id": summary.profile_id, "profile_sha256": summary.profile_sha256,
        "serial": summary.serial, "revision": summary.revision,
        "vendor_id": identity.get("vendor-id (1018h.1)"), "product_code": identity.get("product code (1018h.2)"),
        "device_name": identity.get("device name (1008h)"), "overall": summary.overall,
        "could_not_test": summary.could_not_test, "station": summary.station, "operator": summary.operator,
        "report_dir": summary.report_dir, "exit_code": summary.exit_code,
        "device_restored": None if summary.device_restored is None else int(summary.device_restored),
        "identity": json.dumps(identity), "settings": json.dumps(summary.settings),
    }
    with connect(db_path) as db, db:
        db.execute("BEGIN IMMEDIATE")  # take the write lock now (a parallel run's writer waits, never fails)
        run_id = db.execute(f"INSERT INTO runs ({', '.join(row)}) VALUES ({', '.join('?' * len(row))})",
                            list(row.values())).lastrowid
        db.executemany("INSERT INTO areas VALUES (?, ?, ?, ?, ?, ?, ?)",
                       [(run_id, a.area, a.passed, a.failed, a.warnings, a.skipped, a.verdict)
                        for a in summary.areas()])
        db.executemany("INSERT OR REPLACE INTO results VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                       [(run_id, r.nodeid, r.area, r.outcome, r.basis, r.source, r.message, r.duration_s)
                        for r in summary.results])
    assert run_id is not None
    return run_id


def note_certificate(db_path: Path, run_id: int, certificate: Path) -> None:
    with connect(db_path) as db, db:
        db.execute("UPDATE runs SET certificate = ? WHERE id = ?", (str(certificate), run_id))


@dataclass(frozen=True)
class Filters:
    """What ``history list`` and ``export`` select; None selects everything."""

    serial: str | None = None
    since_utc: str | None = None  # ISO 8601 in UTC
    profile: str | None = None
    kind: str | None = None


def list_runs(db_path: Path, filters: Filters = Filters()) -> list[sqlite3.Row]:
    """The runs matching ``filters``, oldest first."""
    clauses, values = [], []
    for column, value in (("serial", filters.serial), ("profile_id", filters.profile), ("kind", filters.kind)):
        if value is not None:
            clauses.append(f"{column} = ?")
            values.append(value)
    if filters.since_utc is not None:
        clauses.append("started_utc >= ?")
        values.append(filters.since_utc)
    where = f"WHERE {' AND '.join(clauses)}" if clauses else ""
    with connect(db_path, create=False) as db:
        return db.execute(f"SELECT * FROM runs {where} ORDER BY started_utc, id", values).fetchall()


@dataclass
class StoredRun:
    """One run as the history holds it."""

    run: sqlite3.Row
    areas: list[sqlite3.Row]
    results: list[sqlite3.Row]

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


def _stored(db: sqlite3.Connection, run: sqlite3.Row) -> StoredRun:
    areas = db.execute("SELECT * FROM areas WHERE run_id = ? ORDER BY rowid", (run["id"],)).fetchall()
    results = db.execute("SELECT * FROM results WHERE run_id = ? ORDER BY rowid", (run["id"],)).fetchall()
    return StoredRun(run, areas, results)


def get_run(db_path: Path, run_id: int) -> StoredRun | None:
    with connect(db_path, create=False) as db:
        run = db.execute("SELECT * FROM runs WHERE id = ?", (run_id,)).fetchone()
        return None if run is None else _stored(db, run)


def load_runs(db_path: Path, filters: Filters = Filters()) -> list[StoredRun]:
    """The runs matching ``filters`` in full (areas and results), oldest first."""
    ids = [run["id"] for run in list_runs(db_path, filters)]
    with connect(db_path, create=False) as db:
        return [_stored(db, db.execute("SELECT * FROM runs WHERE id = ?", (i,)).fetchone()) for i in ids]
