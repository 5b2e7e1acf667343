"""One run into the history: its row, its areas and every test's outcome, in one transaction, once.

Every record carries its run's own key (a uuid the run gives it, also in its spool file): ``runs.run_key`` is
UNIQUE, so a record sent twice (a spool file sent by two runs at once, or by a run killed after the database's
commit and before the spool file was deleted) leaves one row, and the second sender learns the id of the first.
"""

from __future__ import annotations

import json
from datetime import UTC, datetime

from encoder_conformance.history.dbapi import Db
from encoder_conformance.run_summary import RunSummary

_RUN_COLUMNS = ("run_key", "kind", "started", "started_utc", "duration_s", "profile_id", "profile_sha256", "serial",
                "revision", "vendor_id", "product_code", "device_name", "overall", "could_not_test", "station",
                "operator", "report_dir", "exit_code", "device_restored", "identity", "settings", "certificate")


def utc(started: str) -> str:
    """ISO 8601 in UTC (seconds), as ``started_utc`` holds it: comparable as text."""
    moment = datetime.fromisoformat(started)
    return (moment if moment.tzinfo else moment.astimezone()).astimezone(UTC).isoformat(timespec="seconds")


def _row(summary: RunSummary, key: str, certificate: str | None) -> dict[str, object]:
    identity = summary.identity
    return {
        "run_key": key, "kind": summary.kind, "started": summary.started, "started_utc": utc(summary.started),
        "duration_s": summary.duration_s, "profile_id": summary.profile_id, "profile_sha256": summary.profile_sha256,
        "serial": summary.serial, "revision": summary.revision,
        "vendor_id": identity.get("vendor-id (1018h.1)"), "product_code": identity.get("product code (1018h.2)"),
        "device_name": identity.get("device name (1008h)"), "overall": summary.overall,
        "could_not_test": summary.could_not_test, "station": summary.station, "operator": summary.operator,
        "report_dir": summary.report_dir, "exit_code": summary.exit_code,
        "device_restored": None if summary.device_restored is None else int(summary.device_restored),
        "identity": json.dumps(identity), "settings": json.dumps(summary.settings), "certificate": certificate,
    }


def insert_run(db: Db, summary: RunSummary, key: str, certificate: str | None = None) -> tuple[int, bool]:
    """Record ``summary`` under ``key`` in one transaction: (its id, True), or (the id it already has, False)."""
    row = _row(summary, key, certificate)
    with db.transaction():
        there = db.value("SELECT id FROM runs WHERE run_key = ?", (key,))  # (an id an insert skipped is not reused)
        if there is not None:
            return int(there), False
        inserted = db.rows(f"INSERT INTO runs ({', '.join(_RUN_COLUMNS)}) VALUES ({', '.join('?' * len(row))}) "
                          "ON CONFLICT (run_key) DO NOTHING RETURNING id", [row[c] for c in _RUN_COLUMNS])
        if not inserted:
            return int(db.value("SELECT id FROM runs WHERE run_key = ?", (key,))), False
        run_id = int(inserted[0]["id"])
        db.many("INSERT INTO areas (run_id, area, passed, failed, warnings, skipped, verdict, seq) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                [(run_id, a.area, a.passed, a.failed, a.warnings, a.skipped, a.verdict, n)
                 for n, a in enumerate(summary.areas())])
        results = {r.nodeid: r for r in summary.results}  # a test reported twice: its last outcome counts
        insert_results(db, [(run_id, r.nodeid, r.area, r.outcome, r.basis, r.source, r.message, r.duration_s, n)
                            for n, r in enumerate(results.values())])
    return run_id, True


def insert_results(db: Db, rows: list[tuple[object, ...]]) -> None:
    """(A function of its own so that a test can stop a writer here, between its rows and its commit.)"""
    db.many("INSERT INTO results (run_id, nodeid, area, outcome, basis, source, message, duration_s, seq) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)", rows)


def note_certificate(db: Db, run_id: int, certificate: str) -> None:
    with db.transaction():
        db.run("UPDATE runs SET certificate = ? WHERE id = ?", (certificate, run_id))
