"""What the page reads: a page of runs, one serial number's runs, the pass rates and failing areas per station
and per profile. Only SELECTs; the list is paginated and every filter is on an indexed column (schema.py), so
the list and a filter answer in milliseconds also with tens of thousands of runs."""

from __future__ import annotations

from encoder_conformance.history.dbapi import Db, Row
from encoder_conformance.history.web.params import PageFilters
from encoder_conformance.history.web.plot import Group

PAGE_SIZE = 50
_LIST_COLUMNS = ("id, kind, started, started_utc, profile_id, serial, revision, overall, station, operator, "
                 "device_name, duration_s")
_PASSED = "CASE WHEN overall IN ('PASS', 'PASS WITH WARNINGS') THEN 1 ELSE 0 END"


def runs_page(db: Db, filters: PageFilters, page: int) -> tuple[int, list[Row]]:
    """(how many runs match, the ``page``-th PAGE_SIZE of them, newest first)."""
    where, values = filters.where()
    total = int(db.value(f"SELECT count(*) AS n FROM runs {where}", values))
    rows = db.rows(f"SELECT {_LIST_COLUMNS} FROM runs {where} ORDER BY started_utc DESC, id DESC LIMIT ? OFFSET ?",
                   [*values, PAGE_SIZE, (page - 1) * PAGE_SIZE])
    return total, rows


def choices(db: Db) -> dict[str, list[str]]:
    """The stations and profiles the history holds (the form's lists)."""
    return {"station": [r["v"] for r in db.rows("SELECT DISTINCT station AS v FROM runs WHERE station IS NOT NULL "
                                                "ORDER BY station")],
            "profile": [r["v"] for r in db.rows("SELECT DISTINCT profile_id AS v FROM runs ORDER BY profile_id")]}


def run_row(db: Db, run_id: int) -> Row | None:
    return db.one("SELECT * FROM runs WHERE id = ?", (run_id,))


def timeline(db: Db, serial: str) -> tuple[list[Row], dict[int, dict[str, str]]]:
    """One serial number's runs, oldest first, and each run's verdict per area."""
    runs = db.rows(f"SELECT {_LIST_COLUMNS} FROM runs WHERE serial = ? ORDER BY started_utc, id", (serial,))
    areas: dict[int, dict[str, str]] = {run["id"]: {} for run in runs}
    for row in db.rows("SELECT a.run_id, a.area, a.verdict FROM areas a JOIN runs r ON r.id = a.run_id "
                       "WHERE r.serial = ?", (serial,)):
        areas[row["run_id"]][row["area"]] = row["verdict"]
    return runs, areas


def groups(db: Db, filters: PageFilters, column: str) -> list[Group]:
    """Per ``column`` (station or profile_id): runs, passed, and the areas with the most failed runs."""
    assert column in ("station", "profile_id")
    where, values = filters.where()
    found = {row["name"]: Group(row["name"] or "", int(row["runs"]), int(row["passed"] or 0))
             for row in db.rows(f"SELECT {column} AS name, count(*) AS runs, sum({_PASSED}) AS passed FROM runs "
                                f"{where} GROUP BY {column} ORDER BY count(*) DESC, {column}", values)}
    where_r, values_r = filters.where("r.")
    failed = "a.verdict = 'FAIL'"
    where_r = f"{where_r} AND {failed}" if where_r else f"WHERE {failed}"
    for row in db.rows(f"SELECT r.{column} AS name, a.area AS area, count(*) AS n FROM areas a "
                       f"JOIN runs r ON r.id = a.run_id {where_r} GROUP BY r.{column}, a.area "
                       "ORDER BY count(*) DESC, a.area", values_r):
        if row["name"] in found:
            found[row["name"]].failing.append((row["area"], int(row["n"])))
    return list(found.values())
