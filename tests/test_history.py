"""The run history and the certificate: recording, the ``history`` command, two writers at once, a broken
database that must not fail a run, the certificate's content, and one run against the twin end to end."""

from __future__ import annotations

import csv
import io
import json
import os
import sqlite3
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

from encoder_conformance.cli.main import main
from encoder_conformance.history import certificate, db
from encoder_conformance.run_summary import MODULE_AREAS, RunSummary, TestResult, area_of

REPO = Path(__file__).resolve().parents[1]
SHA = "ab" * 32
SERIAL_KEY = "serial number (1018h.4)"


def _summary(serial: int, started: str, sdo: str = "passed", kind: str = "accept", **extra) -> RunSummary:
    results = [
        TestResult("suites/test_identity.py::test_vendor", "identity", "passed", "cia"),
        TestResult("suites/test_identity.py::test_serial", "identity", "passed", "manual"),
        TestResult("suites/test_sdo_protocol.py::test_expedited", "SDO", sdo, "cia",  # type: ignore[arg-type]
                   "CiA 301 §7.2.4.3", "" if sdo == "passed" else "expected 4 bytes\nobserved 2 bytes"),
        TestResult("suites/test_nmt.py::test_reset_node", "NMT", "skipped", message="needs a power switch"),
    ]
    return RunSummary(
        kind=kind, started=started, profile_id="wachendorff-wdga-mt", profile_sha256=SHA, duration_s=3.25,
        identity={"vendor-id (1018h.1)": "0x0100021F", "product code (1018h.2)": "0x57444741",
                  "revision (1018h.3)": "0x03060208", SERIAL_KEY: f"{serial} (0x{serial:08X})",
                  "device name (1008h)": "WDGA <MT>"},
        settings={"interface": "pcan (from station goods-in.toml)", "bitrate": "250000 (from station goods-in.toml)"},
        station="goods-in-2", operator="J. Meyer", results=results, exit_code=0 if sdo == "passed" else 1,
        device_restored=True, report_dir=f"/srv/reports/{serial}-{started[:10]}", **extra)


@pytest.fixture
def history(tmp_path: Path) -> Path:
    """Three runs: serial 111 passes in January, fails SDO in June; serial 222 passes in June."""
    path = tmp_path / "history.sqlite"
    for summary in (_summary(111, "2026-01-10T09:00:00+01:00"),
                    _summary(111, "2026-06-02T10:30:00+02:00", sdo="failed"),
                    _summary(222, "2026-06-03T08:00:00+02:00", kind="run")):
        db.record_run(summary, path)
    return path


def _history(capsys, *args: str) -> tuple[int, str, str]:
    status = main(["history", *args])
    out, err = capsys.readouterr()
    return status, out, err


def _ids(table: str) -> list[int]:
    return [int(line.split()[0]) for line in table.splitlines()[1:]]


def test_list_selects_by_serial_since_profile_and_kind(history, capsys):
    assert _ids(_history(capsys, "list", "--db", str(history))[1]) == [1, 2, 3]
    status, out, _ = _history(capsys, "list", "--db", str(history), "--serial", "111")
    assert status == 0
    assert _ids(out) == [1, 2]
    assert _ids(_history(capsys, "list", "--db", str(history), "--serial", "0x0000006F")[1]) == [1, 2]
    assert out.splitlines()[0].split() == ["id", "date", "kind", "profile", "serial", "revision", "verdict",
                                           "station", "operator"]
    assert "FAIL" in out.splitlines()[2]
    assert "J. Meyer" in out
    assert "0x03060208" in out
    assert _ids(_history(capsys, "list", "--db", str(history), "--since", "2026-06-01")[1]) == [2, 3]
    # an ISO date-time with an offset: 08:00+02:00 is 06:00 UTC, run 3 started exactly then
    assert _ids(_history(capsys, "list", "--db", str(history), "--since", "2026-06-03T08:00+02:00")[1]) == [3]
    assert _ids(_history(capsys, "list", "--db", str(history), "--kind", "accept", "--serial", "111",
                         "--since", "2026-02-01")[1]) == [2]
    assert "no run" in _history(capsys, "list", "--db", str(history), "--profile", "waycon-sx")[1]


def test_show_gives_areas_failures_settings_and_report_folder(history, capsys):
    status, out, _ = _history(capsys, "show", "2", "--db", str(history))
    assert status == 0
    assert "verdict: FAIL" in out
    assert "SDO       FAIL" in out
    assert "identity  PASS" in out
    assert "suites/test_sdo_protocol.py::test_expedited: expected 4 bytes" in out
    assert "bitrate: 250000 (from station goods-in.toml)" in out
    assert "report folder: /srv/reports/111-2026-06-02" in out
    assert "certificate: none yet" in out


def test_show_certificate_writes_it_for_any_run(history, tmp_path, capsys):
    status, out, _ = _history(capsys, "show", "3", "--db", str(history), "--certificate", "-o", str(tmp_path))
    assert status == 0
    page = (tmp_path / certificate.HTML_NAME).read_text(encoding="utf-8")
    assert "Conformance run certificate" in page
    assert "222" in page
    assert f"certificate: {tmp_path / certificate.HTML_NAME}" in out
    assert db.get_run(history, 3).run["certificate"] == str(tmp_path / certificate.HTML_NAME)


def test_export_csv_and_json(history, tmp_path, capsys):
    status, out, _ = _history(capsys, "export", "--format", "csv", "--db", str(history), "--serial", "111")
    assert status == 0
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [(r["id"], r["overall"], r["serial"]) for r in rows] == [("1", "PASS", "111"), ("2", "FAIL", "111")]
    assert rows[1]["areas"] == "identity=PASS; SDO=FAIL; NMT=NOT RUN"
    assert rows[0]["profile_sha256"] == SHA
    assert rows[0]["station"] == "goods-in-2"
    target = tmp_path / "export.json"
    status, _, err = _history(capsys, "export", "--format", "json", "--db", str(history), "--since", "2026-06-01",
                              "-o", str(target))
    assert status == 0
    assert "wrote 2 run(s)" in err
    runs = json.loads(target.read_text(encoding="utf-8"))
    assert [r["id"] for r in runs] == [2, 3]
    assert runs[0]["identity"][SERIAL_KEY] == "111 (0x0000006F)"
    assert {r["nodeid"]: r["outcome"] for r in runs[0]["results"]}["suites/test_sdo_protocol.py::test_expedited"] \
        == "failed"
    assert runs[0]["areas"][1] == {"area": "SDO", "passed": 0, "failed": 1, "warnings": 0, "skipped": 0,
                                   "verdict": "FAIL"}


def test_compare_two_runs_of_one_serial(history, capsys):
    status, out, _ = _history(capsys, "compare", "1", "2", "--db", str(history))
    assert status == 0
    assert "not the same device" not in out
    assert "areas: 1 changed" in out
    assert "  SDO: PASS -> FAIL" in out
    assert "suites/test_sdo_protocol.py::test_expedited: passed -> failed (expected 4 bytes)" in out
    assert "tests: 1 of 4 run in both changed outcome\n" in out
    _, other, _ = _history(capsys, "compare", "2", "3", "--db", str(history))
    assert "not the same device (serial 111 vs 222)" in other


def test_compare_counts_the_tests_only_one_run_ran(tmp_path, capsys):
    path = tmp_path / "history.sqlite"
    full = _summary(111, "2026-06-02T10:30:00+02:00", kind="run")
    accept = _summary(111, "2026-06-03T10:30:00+02:00", sdo="failed")
    accept.results = accept.results[1:3]  # a smaller selection
    db.record_run(full, path)
    db.record_run(accept, path)
    _, out, _ = _history(capsys, "compare", "1", "2", "--db", str(path))
    assert "tests: 1 of 2 run in both changed outcome; 2 only in A, 0 only in B (another selection)" in out
    assert "  NMT: NOT RUN -> -" in out


@pytest.mark.parametrize(("args", "names"), [
    (["show", "42"], "RUN_ID 42"),
    (["show", "x1"], "RUN_ID 'x1'"),
    (["compare", "1", "99"], "RUN_B 99"),
    (["list", "--since", "26.11.2026"], "--since '26.11.2026'"),
    (["list", "--serial", "0xZZ"], "--serial '0xZZ'"),
    (["export", "--since", "yesterday"], "--since 'yesterday'"),
])
def test_usage_errors_are_one_line_with_exit_code_4(history, capsys, args, names):
    status, out, err = _history(capsys, *args, "--db", str(history))
    assert status == 4
    assert len(err.strip().splitlines()) == 1
    assert names in err
    assert "Traceback" not in err
    assert out == ""


def test_a_missing_database_is_a_usage_error(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv(db.ENV_VAR, str(tmp_path / "nowhere.sqlite"))
    status, _, err = _history(capsys, "list")
    assert status == 4
    assert err.count("\n") == 1
    assert "nowhere.sqlite: no history database there; give --db PATH" in err
    status, _, err = _history(capsys, "list", "--db", str(tmp_path / "other.sqlite"))
    assert status == 4
    assert err.startswith("history list: --db ")


def test_the_path_comes_from_option_station_environment_then_repository(tmp_path, monkeypatch):
    monkeypatch.delenv(db.ENV_VAR, raising=False)
    assert db.history_path() == REPO / "reports" / "history.sqlite"
    monkeypatch.setenv(db.ENV_VAR, str(tmp_path / "env.sqlite"))
    assert db.history_path() == tmp_path / "env.sqlite"
    assert db.history_path(None, tmp_path / "station.sqlite") == tmp_path / "station.sqlite"
    assert db.history_path(str(tmp_path / "opt.sqlite"), tmp_path / "station.sqlite") == tmp_path / "opt.sqlite"


def test_the_station_file_names_the_database(history, tmp_path, capsys):
    station = tmp_path / "goods-in.toml"
    station.write_text(f'station = "goods-in-2"\nhistory = "{history.name}"\n', encoding="utf-8")
    assert _ids(_history(capsys, "list", "--station", str(station))[1]) == [1, 2, 3]


def _write_many(args: tuple[str, int]) -> list[int]:
    path, serial = args
    return [db.record_run(_summary(serial, f"2026-03-01T10:{n:02d}:00+01:00"), Path(path)) for n in range(15)]


def test_two_writers_at_once_neither_fails_nor_loses_a_run(tmp_path):
    path = tmp_path / "shared.sqlite"  # created by the first of the two writers, as on a fresh station
    with ProcessPoolExecutor(max_workers=2) as pool:
        ids = list(pool.map(_write_many, [(str(path), 111), (str(path), 222)]))
    assert sorted(ids[0] + ids[1]) == list(range(1, 31))
    assert len(db.list_runs(path)) == 30  # (a later connection switches to WAL where the first two could not)
    with sqlite3.connect(path) as check:
        assert check.execute("SELECT count(*) FROM results").fetchone()[0] == 30 * 4
        assert check.execute("PRAGMA journal_mode").fetchone()[0] == "wal"


def test_a_locked_database_gives_up_with_a_history_error(tmp_path, monkeypatch):
    path = tmp_path / "locked.sqlite"
    db.record_run(_summary(111, "2026-03-01T10:00:00+01:00"), path)
    monkeypatch.setattr(db, "BUSY_TIMEOUT_S", 0.2)
    holder = sqlite3.connect(path)
    try:
        holder.execute("BEGIN EXCLUSIVE")
        with pytest.raises(db.HistoryError, match="locked"):
            db.record_run(_summary(111, "2026-03-02T10:00:00+01:00"), path)
    finally:
        holder.close()


def test_a_newer_schema_is_refused(tmp_path):
    path = tmp_path / "newer.sqlite"
    with sqlite3.connect(path) as newer:
        newer.execute(f"PRAGMA user_version = {db.SCHEMA_VERSION + 1}")
    with pytest.raises(db.HistoryError, match="newer version of the suite"):
        db.record_run(_summary(111, "2026-03-01T10:00:00+01:00"), path)


def test_the_certificate_holds_what_goods_in_files():
    summary = _summary(111, "2026-06-02T10:30:00+02:00", sdo="failed")
    page = certificate.render_certificate(summary)
    for text in ("Acceptance certificate", ">FAIL<", "111", "0x03060208", SHA, "wachendorff-wdga-mt", "goods-in-2",
                 "J. Meyer", "250000 (from station goods-in.toml)", "Operator's signature",
                 "/srv/reports/111-2026-06-02", "2026-06-02 10:30:00 +0200", "3.2 s", "@page", "A4"):
        assert text in page, text
    assert "WDGA &lt;MT&gt;" in page  # device data is escaped, not markup
    rows = {area: verdict for area, verdict in
            [(cells[0], cells[1]) for cells in _area_rows(page)]}
    assert rows == {"identity": "PASS", "SDO": "FAIL", "NMT": "NOT RUN"}
    assert "expected 4 bytes" in page
    assert "observed 2 bytes" not in page


def _area_rows(page: str) -> list[list[str]]:
    import re

    table = page.split("Verdict per area", 1)[1].split("</table>", 1)[0]
    rows = re.findall(r"<tr><td>(.*?)</td><td><b>(.*?)</b>", table)
    return [list(row) for row in rows]


def test_without_weasyprint_the_html_is_the_certificate(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "weasyprint", None)  # import fails as if not installed
    files = certificate.write_certificate(_summary(111, "2026-06-02T10:30:00+02:00"), tmp_path)
    assert files.html.is_file()
    assert files.pdf is None
    assert "WeasyPrint is not installed" in (files.pdf_note or "")


def test_with_weasyprint_a_one_page_pdf_also_for_the_longest_certificate(tmp_path):
    weasyprint = pytest.importorskip("weasyprint", exc_type=ImportError)
    summary = _summary(111, "2026-06-02T10:30:00+02:00", sdo="failed")
    summary.results += [TestResult(f"suites/{module}.py::test_{n}[some-long-parameter-id-{n}]", area_of(module),
                                   "failed", "cia", "CiA 301", "expected something rather long " * 12)
                        for n, module in enumerate([*MODULE_AREAS, "test_other"])]
    summary.settings.update({"channel": "PCAN_USBBUS1 (from station goods-in.toml)", "node-id": "5 (from --node-id)",
                             "fd": "False (from ~/can.conf)"})
    summary.could_not_test = "the device went silent after test_sdo_block (no heartbeat for 2.5 s)"
    assert len(summary.areas()) == 12
    files = certificate.write_certificate(summary, tmp_path)
    if files.pdf is None:
        pytest.skip(files.pdf_note or "no PDF")
    assert files.pdf.read_bytes().startswith(b"%PDF")
    assert len(weasyprint.HTML(string=certificate.render_certificate(summary)).render().pages) == 1


def _suite_run(tmp_path: Path, name: str, env_history: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("CAN_")}
    env[db.ENV_VAR] = str(env_history)
    command = [sys.executable, "-m", "encoder_conformance", "run", "--profile", "wachendorff-wdga-mt",
               "--report-dir", str(tmp_path / name), "--", "-q", "-k", "test_identity", *extra]
    return subprocess.run(command, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)


def test_an_acceptance_run_against_the_twin_is_recorded_with_its_certificate(tmp_path, capsys):
    history = tmp_path / "history.sqlite"
    run = _suite_run(tmp_path, "accept", history, "--run-kind", "accept")
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert "history: run 1 recorded in" in run.stdout
    serial = json.loads((tmp_path / "accept" / "run-summary.json").read_text())["serial"]
    status, out, _ = _history(capsys, "list", "--db", str(history), "--serial", serial)
    assert status == 0
    assert _ids(out) == [1]
    assert " accept " in out
    assert " PASS " in out
    assert (tmp_path / "accept" / certificate.HTML_NAME).is_file()
    assert f"certificate: {tmp_path / 'accept' / certificate.HTML_NAME}" in _history(capsys, "show", "1", "--db",
                                                                                      str(history))[1]


def test_a_broken_history_warns_once_and_the_verdict_stands(tmp_path):
    """The station file's history (over the environment's) is a text file: one warning, exit status 0."""
    broken = tmp_path / "broken.sqlite"
    broken.write_bytes(b"this is not an SQLite database, but a text file someone saved here" * 20)
    station = tmp_path / "goods-in.toml"
    station.write_text(f'station = "goods-in-2"\nhistory = "{broken.name}"\n', encoding="utf-8")
    run = _suite_run(tmp_path, "broken", tmp_path / "environment.sqlite", "--station", str(station))
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    warnings = [line for line in run.stdout.splitlines() if line.startswith("history:")]
    assert len(warnings) == 1
    assert f"{broken}: file is not a database" in warnings[0]
    assert "this run was not recorded" in warnings[0]
    assert "verdict stands" in warnings[0]
    assert "Traceback" not in run.stdout + run.stderr
    assert not (tmp_path / "environment.sqlite").exists()
