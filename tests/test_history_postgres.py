"""The history on PostgreSQL: the same commands and output as on SQLite, the versioned schema (upgrade, refusal,
a user who may not upgrade), eight acceptance runs at once, the server stopped half-way (every verdict stands,
every record arrives once after ``history sync``), a writer killed before its commit, and the page.

A real server: Debian's postgresql package (CI installs it), started here on a temporary folder and a free
loopback port (as the postgres user where the tests run as root); without its binaries these tests skip.
"""

from __future__ import annotations

import contextlib
import glob
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from test_history import _summary

from encoder_conformance.history import db, schema, spool
from encoder_conformance.history.backend import open_db
from encoder_conformance.history.target import PostgresUrl

psycopg = pytest.importorskip("psycopg", reason="psycopg is not installed (pip install -e '.[dev]')")

REPO = Path(__file__).resolve().parents[1]
PROFILE = "wachendorff-wdga-mt"
STATIONS = 8


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class PgServer:
    """A throw-away PostgreSQL cluster: initdb, pg_ctl start/stop, one database per test."""

    def __init__(self, bindir: Path) -> None:
        self.bindir = bindir
        self.base = Path(tempfile.mkdtemp(prefix="ec-history-pg-"))
        self.data = self.base / "data"
        self.port = _free_port()
        self.as_user: list[str] = []
        if os.geteuid() == 0:  # the server refuses to run as root
            shutil.chown(self.base, "postgres", "postgres")
            self.as_user = ["runuser", "-u", "postgres", "--"]
        self._databases = 0
        self._pg("initdb", "-D", str(self.data), "-U", "postgres", "-A", "trust", "-E", "UTF8", "--no-sync")

    def _pg(self, program: str, *args: str) -> None:
        done = subprocess.run([*self.as_user, str(self.bindir / program), *args], capture_output=True, text=True,
                              timeout=120, cwd=self.base)
        if done.returncode != 0:
            log = (self.base / "server.log").read_text() if (self.base / "server.log").exists() else ""
            raise RuntimeError(f"{program} failed: {done.stdout}{done.stderr}{log[-2000:]}")

    def start(self) -> None:
        options = (f"-p {self.port} -k {self.base} -c listen_addresses=127.0.0.1 -c fsync=off "
                   "-c synchronous_commit=off -c full_page_writes=off")
        self._pg("pg_ctl", "-D", str(self.data), "-l", str(self.base / "server.log"), "-w", "-t", "60",
                 "-o", options, "start")

    def stop(self, mode: str = "fast") -> None:
        self._pg("pg_ctl", "-D", str(self.data), "-m", mode, "-w", "stop")

    def url(self, database: str = "postgres", user: str = "postgres") -> str:
        return f"postgresql://{user}@127.0.0.1:{self.port}/{database}"

    def admin(self, sql: str, database: str = "postgres") -> None:
        with psycopg.connect(self.url(database), autocommit=True) as connection:
            connection.execute(sql)

    def new_database(self) -> str:
        self._databases += 1
        name = f"history_{self._databases}"
        self.admin(f"CREATE DATABASE {name}")
        return self.url(name)

    def close(self) -> None:
        with contextlib.suppress(RuntimeError):  # stopped already
            self.stop("immediate")
        shutil.rmtree(self.base, ignore_errors=True)


def _bindir() -> Path | None:
    found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"), key=lambda p: int(Path(p).parts[-3]))
    if found:
        return Path(found[-1]).parent
    initdb = shutil.which("initdb")
    return Path(initdb).parent if initdb else None


@pytest.fixture(scope="module")
def server():
    bindir = _bindir()
    if bindir is None:
        pytest.skip("no PostgreSQL server here (apt-get install postgresql; CI installs it)")
    if os.geteuid() == 0 and shutil.which("runuser") is None:
        pytest.skip("running as root without runuser: the PostgreSQL server cannot be started as another user")
    pg = PgServer(bindir)
    try:
        pg.start()
        yield pg
    finally:
        pg.close()


@pytest.fixture
def url(server) -> str:
    return server.new_database()


def _history(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "encoder_conformance", "history", *args], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=120)


def _count(url: str, sql: str = "SELECT count(*) FROM runs") -> int:
    with psycopg.connect(url) as connection:
        return int(connection.execute(sql).fetchone()[0])


def _recorded(url: str) -> int:
    try:
        return _count(url)
    except psycopg.errors.UndefinedTable:  # no run has made the tables yet
        return 0


def _three_runs(target) -> None:
    for summary in (_summary(111, "2026-01-10T09:00:00+01:00"),
                    _summary(111, "2026-06-02T10:30:00+02:00", sdo="failed"),
                    _summary(222, "2026-06-03T08:00:00+02:00", kind="run")):
        db.record_run(summary, target)


def test_the_history_commands_print_the_same_on_postgresql_as_on_sqlite(url, tmp_path):
    sqlite = tmp_path / "history.sqlite"
    _three_runs(sqlite)
    _three_runs(PostgresUrl(url))
    for command in (["list"], ["list", "--serial", "111", "--since", "2026-02-01"], ["show", "2"],
                    ["export", "--format", "json"], ["export", "--format", "csv", "--kind", "accept"],
                    ["compare", "1", "2"]):
        on_sqlite, on_postgres = _history(*command, "--db", str(sqlite)), _history(*command, "--db", url)
        assert on_postgres.returncode == on_sqlite.returncode == 0, on_postgres.stderr
        assert on_postgres.stdout == on_sqlite.stdout, command
    assert _count(url, "SELECT count(*) FROM results") == 3 * 4


def test_a_fresh_database_gets_the_current_schema_and_an_older_one_is_upgraded(server, url):
    db.record_run(_summary(111, "2026-01-10T09:00:00+01:00"), PostgresUrl(url))
    assert _count(url, "SELECT max(version) FROM schema_version") == schema.SCHEMA_VERSION
    older = server.new_database()
    with psycopg.connect(older, autocommit=True) as connection:  # as version 1 would have left it
        for statement in schema.steps("postgresql")[0]:
            connection.execute(statement)
        connection.execute("INSERT INTO schema_version VALUES (1)")
    run_id = db.record_run(_summary(222, "2026-01-11T09:00:00+01:00"), PostgresUrl(older), key="k-1")
    assert _count(older, "SELECT max(version) FROM schema_version") == schema.SCHEMA_VERSION
    assert db.record_new(_summary(222, "2026-01-11T09:00:00+01:00"), PostgresUrl(older), key="k-1") == (run_id, False)


def test_a_newer_schema_is_refused(url):
    db.record_run(_summary(111, "2026-01-10T09:00:00+01:00"), PostgresUrl(url))
    with psycopg.connect(url, autocommit=True) as connection:
        connection.execute("UPDATE schema_version SET version = %s", (schema.SCHEMA_VERSION + 1,))
    with pytest.raises(db.HistoryError, match="newer version of the suite"):
        db.record_run(_summary(111, "2026-01-11T09:00:00+01:00"), PostgresUrl(url))
    listing = _history("list", "--db", url)
    assert listing.returncode == 4
    assert "newer version of the suite" in listing.stderr
    assert len(listing.stderr.strip().splitlines()) == 1


def test_a_station_user_who_may_not_upgrade_is_told_what_to_run(server, url):
    database = url.rsplit("/", 1)[1]
    with psycopg.connect(url, autocommit=True) as connection:
        for statement in schema.steps("postgresql")[0]:
            connection.execute(statement)
        connection.execute("INSERT INTO schema_version VALUES (1)")
        connection.execute("DROP ROLE IF EXISTS station; CREATE ROLE station LOGIN")
        connection.execute("GRANT SELECT, INSERT, UPDATE ON ALL TABLES IN SCHEMA public TO station")
    station = PostgresUrl(server.url(database, user="station"))
    with pytest.raises(db.HistoryError) as refused:
        db.record_run(_summary(111, "2026-01-10T09:00:00+01:00"), station)
    assert "user 'station' may not change it" in str(refused.value)
    assert "encoder-conformance history upgrade --db postgresql://OWNER@HOST/DATABASE" in str(refused.value)
    done = _history("upgrade", "--db", url)
    assert done.returncode == 0, done.stderr
    assert f"schema {schema.SCHEMA_VERSION} (upgraded from 1)" in done.stdout
    assert "already current" in _history("upgrade", "--db", url).stdout


def test_a_record_sent_by_eight_senders_at_once_is_recorded_once(url):
    summary = _summary(111, "2026-01-10T09:00:00+01:00")
    with ThreadPoolExecutor(max_workers=STATIONS) as pool:
        outcomes = list(pool.map(lambda _: db.record_new(summary, PostgresUrl(url), key="same-run"),
                                 range(STATIONS)))
    assert len({run_id for run_id, _ in outcomes}) == 1
    assert sum(new for _, new in outcomes) == 1
    assert _count(url) == 1
    assert _count(url, "SELECT count(*) FROM results") == 4


_KILLED_WRITER = """
import os, signal, sys
from pathlib import Path
from encoder_conformance.history import db, records, spool
from encoder_conformance.history.target import parse_target, target_key
from encoder_conformance.run_summary import RunSummary
summary = RunSummary.read(Path(sys.argv[2]))
target = parse_target(sys.argv[1])
spool.put(Path(sys.argv[3]), "killed-run", target_key(target), summary)
def die(database, rows):
    original(database, rows)  # the rows are written, the commit has not happened
    os.kill(os.getpid(), signal.SIGKILL)
original, records.insert_results = records.insert_results, die
db.record_run(summary, target, key="killed-run")
"""


@pytest.mark.parametrize("kind", ["postgresql", "sqlite"])
def test_a_writer_killed_before_its_commit_leaves_nothing_half_written(request, tmp_path, kind):
    target = request.getfixturevalue("url") if kind == "postgresql" else str(tmp_path / "history.sqlite")
    summary_file = tmp_path / "run-summary.json"
    summary_file.write_text(_summary(111, "2026-01-10T09:00:00+01:00").to_json(), encoding="utf-8")
    folder = tmp_path / spool.FOLDER_NAME
    killed = subprocess.run([sys.executable, "-c", _KILLED_WRITER, target, str(summary_file), str(folder)],
                            cwd=REPO, capture_output=True, text=True, timeout=60)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    with open_db(db.history_path(target)) as check:
        assert check.value("SELECT count(*) AS n FROM runs") == 0
        assert check.value("SELECT count(*) AS n FROM results") == 0
    assert [p.name for p in folder.iterdir()] == ["killed-run.json"]
    first = _history("sync", "--db", target, "--spool", str(folder))
    assert first.returncode == 0, first.stderr
    assert first.stdout.startswith("sent 1 run(s) to ")
    assert "sent 0 run(s)" in _history("sync", "--db", target, "--spool", str(folder)).stdout
    assert len(db.list_runs(db.history_path(target))) == 1
    assert list(folder.iterdir()) == []


def _accept(tmp_path: Path, n: int, history: str) -> subprocess.Popen[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
    command = [sys.executable, "-m", "encoder_conformance", "accept", "--profile", PROFILE, "--report-dir",
               str(tmp_path / "reports" / f"station-{n}"), "--history", history]
    return subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


#: seconds between two stations' starts. Eight runs and eight twins started in the same instant on two cores left
#: a twin's SDO answer later than the 300 ms a tester waits (one FAIL in 3 CI runs, a start-up reply or a factory
#: default): the device checks are not what these tests are about. Each run takes ~2.5 s, so the eight still
#: overlap and still write to the database at nearly the same time.
STAGGER_S = 0.2


def _stations(tmp_path: Path, history: str) -> list[subprocess.Popen[str]]:
    runs = []
    for n in range(STATIONS):
        if n:
            threading.Event().wait(STAGGER_S)  # pacing the starts, not waiting for a device
        runs.append(_accept(tmp_path, n, history))
    return runs


def _finish(runs: list[subprocess.Popen[str]]) -> list[str]:
    outputs = []
    for run in runs:
        out, _ = run.communicate(timeout=300)
        assert run.returncode == 0, out[-3000:]
        # the verdict, as without a history: eight stations on two cores may leave a timing check inconclusive
        assert out.splitlines()[-1].startswith(("PASS (", "PASS WITH WARNINGS (")), out[-3000:]
        outputs.append(out)
    return outputs


def test_eight_stations_at_once_record_eight_runs(url, tmp_path):
    outputs = _finish(_stations(tmp_path, url))
    assert sum("history: run " in out and " recorded in postgresql://" in out for out in outputs) == STATIONS
    assert _count(url) == STATIONS
    assert _count(url, "SELECT count(DISTINCT run_key) FROM runs") == STATIONS
    assert not list((tmp_path / "reports" / spool.FOLDER_NAME).glob("*.json"))


def test_the_server_stopped_midway_loses_no_run_and_duplicates_none(server, url, tmp_path):
    runs = _stations(tmp_path, url)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and _recorded(url) == 0:
        time.sleep(0.05)
    server.stop()
    try:
        outputs = _finish(runs)
    finally:
        server.start()
    recorded = sum(" recorded in postgresql://" in out for out in outputs)
    # a run still connected sends what an earlier one left waiting (its line says how many): counted once there
    sent_for_others = sum(int(n) for out in outputs for n in re.findall(r"history: (\d+) earlier run\(s\) sent", out))
    waiting = sorted((tmp_path / "reports" / spool.FOLDER_NAME).glob("*.json"))
    assert recorded + sent_for_others + len(waiting) == STATIONS
    assert all("the record waits in" in out for out in outputs if " recorded in postgresql://" not in out)
    done = _history("sync", "--db", url, "--spool", str(tmp_path / "reports" / spool.FOLDER_NAME))
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.startswith(f"sent {len(waiting)} run(s) to postgresql://")
    assert _count(url) == STATIONS
    assert _count(url, "SELECT count(DISTINCT run_key) FROM runs") == STATIONS
    assert "sent 0 run(s)" in _history("sync", "--db", url, "--spool",
                                       str(tmp_path / "reports" / spool.FOLDER_NAME)).stdout
    print(f"server stopped after the first record: {recorded} recorded at once, {len(waiting)} spooled and synced")


def test_an_unreachable_database_keeps_the_verdict_and_the_next_run_sends_the_record(server, url, tmp_path):
    server.stop()
    try:
        first = _finish([_accept(tmp_path, 1, url)])[0]
    finally:
        server.start()
    assert "history: this run was not recorded: postgresql://postgres@127.0.0.1" in first
    assert "the record waits in" in first
    second = _finish([_accept(tmp_path, 2, url)])[0]
    assert "history: 1 earlier run(s) sent from" in second
    assert _count(url) == 2


def test_the_page_reads_postgresql(url, tmp_path):
    _three_runs(PostgresUrl(url))
    serve = subprocess.Popen([sys.executable, "-m", "encoder_conformance", "history", "serve", "--db", url,
                              "--listen", "127.0.0.1:0"], cwd=REPO, stdout=subprocess.PIPE, text=True)
    try:
        address = serve.stdout.readline().split()[2]  # "history serve: http://127.0.0.1:PORT/ ..."
        with urllib.request.urlopen(f"{address}?verdict=FAIL", timeout=30) as page:
            text = page.read().decode()
        assert "<b>1</b> run(s) match" in text
        with pytest.raises(urllib.error.HTTPError) as bad:
            urllib.request.urlopen(f"{address}?from=yesterday", timeout=30)
        assert bad.value.code == 400
        assert "from &#39;yesterday&#39;: not a date" in bad.value.read().decode()
        with urllib.request.urlopen(f"{address}run/2", timeout=30) as page:
            assert "expected 4 bytes\nobserved 2 bytes" in page.read().decode()
    finally:
        serve.send_signal(signal.SIGINT)
        serve.wait(timeout=30)
    assert _count(url) == 3  # the page wrote nothing
