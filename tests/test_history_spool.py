"""Where the history is (a file or a PostgreSQL URL), the SQLite schema's upgrade, and nothing lost: the spool a
run writes before its record, ``history sync``, a record sent many times at once recorded once. Without a
PostgreSQL server: the same on SQLite (tests/test_history_postgres.py does it against a server)."""

from __future__ import annotations

import json
import os
import socket
import sqlite3
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest
from test_history import _suite_run, _summary

from encoder_conformance.cli.history import parse_listen
from encoder_conformance.cli.main import main
from encoder_conformance.errors import UsageError
from encoder_conformance.history import db, schema, spool, sync
from encoder_conformance.history.target import PostgresUrl, history_path, parse_target, target_key

REPO = Path(__file__).resolve().parents[1]


def test_a_history_is_a_file_or_a_postgresql_url(tmp_path, monkeypatch):
    assert parse_target("postgresql://qa@db.example/history") == PostgresUrl("postgresql://qa@db.example/history")
    assert parse_target("postgres://qa@db/h") == PostgresUrl("postgres://qa@db/h")
    assert parse_target(str(tmp_path / "h.sqlite")) == tmp_path / "h.sqlite"
    with pytest.raises(db.HistoryError, match="an SQLite file path or a postgresql://"):
        parse_target("mysql://qa@db/history")
    monkeypatch.setenv(db.ENV_VAR, "postgresql://qa@db/history")
    assert history_path() == PostgresUrl("postgresql://qa@db/history")


def test_a_password_is_never_shown():
    url = PostgresUrl("postgresql://qa:s3cret@db:5432/history?sslmode=require&password=other")
    assert "s3cret" not in str(url)
    assert "other" not in str(url)
    assert str(url) == "postgresql://qa:***@db:5432/history?sslmode=require&password=***"
    assert target_key(url) == str(url)


def test_the_station_file_may_name_a_postgresql_url(tmp_path, capsys):
    """The station loader makes 'history' a path under the station's folder; the URL is taken back out."""
    from encoder_conformance.config.station import load_station

    station = tmp_path / "goods-in.toml"
    station.write_text('station = "goods-in-2"\nhistory = "postgresql://qa@db.example:5433/history"\n',
                       encoding="utf-8")
    loaded = load_station(station).history
    assert history_path(None, loaded) == PostgresUrl("postgresql://qa@db.example:5433/history")


def _v1_file(path: Path) -> None:
    """A history as the suite's schema 1 left it, with one run."""
    with sqlite3.connect(path) as old:
        for statement in schema.steps("sqlite")[0]:
            old.execute(statement)
        old.execute("INSERT INTO runs (kind, started, started_utc, profile_id, profile_sha256, overall, identity, "
                    "settings, serial) VALUES ('accept', '2026-01-01T08:00:00+01:00', '2026-01-01T07:00:00+00:00', "
                    "'wachendorff-wdga-mt', 'ab', 'PASS', '{}', '{}', '111')")
        old.execute("PRAGMA user_version = 1")


def test_an_older_sqlite_history_is_upgraded_and_keeps_its_runs(tmp_path, capsys):
    path = tmp_path / "old.sqlite"
    _v1_file(path)
    assert main(["history", "upgrade", "--db", str(path)]) == 0
    assert f"schema {schema.SCHEMA_VERSION} (upgraded from 1)" in capsys.readouterr().out
    second = tmp_path / "old-2.sqlite"
    _v1_file(second)
    assert db.record_run(_summary(111, "2026-02-01T08:00:00+01:00"), second) == 2  # a run upgrades it by itself
    with sqlite3.connect(second) as check:
        assert check.execute("PRAGMA user_version").fetchone()[0] == schema.SCHEMA_VERSION
    assert [r["serial"] for r in db.list_runs(second)] == ["111", "111"]


def test_a_run_key_is_recorded_once(tmp_path):
    path = tmp_path / "h.sqlite"
    summary = _summary(111, "2026-02-01T08:00:00+01:00")
    assert db.record_new(summary, path, key="run-a") == (1, True)
    assert db.record_new(summary, path, key="run-a") == (1, False)
    assert db.record_new(summary, path, key="run-b") == (2, True)
    assert len(db.list_runs(path)) == 2


def test_a_spool_file_is_whole_or_absent(tmp_path):
    folder = tmp_path / spool.FOLDER_NAME
    summary = _summary(111, "2026-02-01T08:00:00+01:00")
    written = spool.put(folder, "k1", "/srv/h.sqlite", summary, "/srv/r/certificate.html")
    (folder / ".k2.json.tmp").write_text('{"format": 1, "run_ke', encoding="utf-8")  # a writer killed mid-write
    assert list(spool.waiting(folder)) == [written]
    record = spool.read(written)
    assert (record.key, record.history, record.certificate) == ("k1", "/srv/h.sqlite", "/srv/r/certificate.html")
    assert record.summary.to_json() == summary.to_json()


def _spooled(folder: Path, target: Path, count: int) -> None:
    for n in range(count):
        spool.put(folder, f"run-{n:03d}", target_key(target), _summary(100 + n, f"2026-03-01T10:{n:02d}:00+01:00"))


def _sync(args: tuple[str, str]) -> tuple[int, int]:
    report = sync.send_waiting(Path(args[0]), Path(args[1]))
    return len(report.sent), len(report.already)


def test_eight_senders_of_one_spool_record_each_run_once(tmp_path):
    target, folder = tmp_path / "h.sqlite", tmp_path / spool.FOLDER_NAME
    _spooled(folder, target, 20)
    with ProcessPoolExecutor(max_workers=8) as pool:
        counts = list(pool.map(_sync, [(str(target), str(folder))] * 8))
    assert sum(sent for sent, _ in counts) == 20
    assert len(db.list_runs(target)) == 20
    assert list(spool.waiting(folder)) == []


def test_history_sync_sends_what_waits_for_its_history_only(tmp_path, capsys):
    target, other, folder = tmp_path / "h.sqlite", tmp_path / "other.sqlite", tmp_path / spool.FOLDER_NAME
    _spooled(folder, target, 3)
    spool.put(folder, "for-the-other", target_key(other), _summary(999, "2026-03-02T10:00:00+01:00"))
    (folder / "notes.json").write_text("not a record", encoding="utf-8")
    assert main(["history", "sync", "--db", str(target), "--spool", str(folder)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"sent 3 run(s) to {target} (ids 1, 2, 3)\n")
    assert f"1 record(s) in {folder} wait for another history: {other}" in out
    assert f"not a spool record, left in place: {folder / 'notes.json'}" in out
    assert main(["history", "sync", "--db", str(target), "--spool", str(folder)]) == 0
    assert capsys.readouterr().out.startswith(f"sent 0 run(s) to {target}\n")
    assert len(db.list_runs(target)) == 3


def _closed_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_history_sync_to_an_unreachable_database_keeps_every_record(tmp_path, capsys):
    pytest.importorskip("psycopg")
    url = f"postgresql://qa@127.0.0.1:{_closed_port()}/history"
    folder = tmp_path / spool.FOLDER_NAME
    spool.put(folder, "waits", target_key(PostgresUrl(url)), _summary(111, "2026-03-02T10:00:00+01:00"))
    assert main(["history", "sync", "--db", url, "--spool", str(folder)]) == 4
    out = capsys.readouterr().out
    assert "stopped: postgresql://qa@127.0.0.1" in out
    assert f"1 record(s) still wait in {folder}" in out
    assert [p.name for p in spool.waiting(folder)] == ["waits.json"]


def test_a_broken_history_keeps_the_record_in_the_spool_and_the_next_run_sends_it(tmp_path):
    history = tmp_path / "history.sqlite"
    history.write_bytes(b"this is not an SQLite database" * 40)
    first = _suite_run(tmp_path, "first", history)
    assert first.returncode == 0, first.stdout[-2000:] + first.stderr[-2000:]
    warnings = [line for line in first.stdout.splitlines() if line.startswith("history:")]
    assert len(warnings) == 1
    assert "file is not a database" in warnings[0]
    waiting = list(spool.waiting(tmp_path / spool.FOLDER_NAME))
    assert f"the record waits in {waiting[0]}" in warnings[0]
    history.unlink()  # the station's administrator fixes it
    second = _suite_run(tmp_path, "second", history)
    assert second.returncode == 0, second.stdout[-2000:] + second.stderr[-2000:]
    assert "history: run 1 recorded in" in second.stdout
    assert f"history: 1 earlier run(s) sent from {tmp_path / spool.FOLDER_NAME}" in second.stdout
    runs = db.list_runs(history)
    assert sorted(Path(r["report_dir"]).name for r in runs) == ["first", "second"]
    assert list(spool.waiting(tmp_path / spool.FOLDER_NAME)) == []
    summary = json.loads((tmp_path / "first" / "run-summary.json").read_text(encoding="utf-8"))
    assert set(summary) >= {"kind", "results"}  # the report is what it was without a history


@pytest.mark.parametrize(("listen", "expected"), [("127.0.0.1:8600", ("127.0.0.1", 8600)),
                                                  ("[::1]:8601", ("::1", 8601)), ("0.0.0.0:80", ("0.0.0.0", 80))])
def test_listen_takes_host_and_port(listen, expected):
    assert parse_listen(listen) == expected


@pytest.mark.parametrize("listen", ["8600", "localhost:", "127.0.0.1:http", "127.0.0.1:70000"])
def test_a_bad_listen_address_is_a_usage_error(listen):
    with pytest.raises(UsageError, match="--listen"):
        parse_listen(listen)


def test_serve_refuses_a_missing_history_and_a_busy_port_in_one_line(tmp_path):
    path = tmp_path / "h.sqlite"
    db.record_run(_summary(111, "2026-03-02T10:00:00+01:00"), path)
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    command = [sys.executable, "-m", "encoder_conformance", "history", "serve"]
    missing = subprocess.run([*command, "--db", str(tmp_path / "none.sqlite")], cwd=REPO, env=env,
                             capture_output=True, text=True, timeout=60)
    assert missing.returncode == 4
    assert missing.stderr.count("\n") == 1
    assert "none.sqlite: no history database there" in missing.stderr
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        taken = subprocess.run([*command, "--db", str(path), "--listen", f"127.0.0.1:{port}"], cwd=REPO, env=env,
                               capture_output=True, text=True, timeout=60)
    assert taken.returncode == 4
    assert taken.stderr.count("\n") == 1
    assert f"--listen 127.0.0.1:{port}: cannot listen there" in taken.stderr
