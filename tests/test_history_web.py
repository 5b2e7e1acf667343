"""``history serve``: the page over HTTP (filters, a run, a timeline, pass rates, bad filters answered with 400
and a message, every value escaped, nothing written, loopback by default), its speed with 10,000 runs, and the
page in headless Chromium (Debian's chromium driven by Playwright): it loads, filters narrow the list, a run's page
shows its failures, a broken filter gives the message. Screenshots go to $HISTORY_SCREENSHOTS where it is set."""

from __future__ import annotations

import hashlib
import os
import random
import shutil
import statistics
import subprocess
import sys
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

from encoder_conformance.history import records
from encoder_conformance.history.backend import open_db
from encoder_conformance.history.target import Target
from encoder_conformance.run_summary import MODULE_AREAS, RunSummary, TestResult

REPO = Path(__file__).resolve().parents[1]
STATIONS = ("goods-in-1", "goods-in-2", "goods-in-3", "lab")
PROFILES = ("wachendorff-wdga-mt", "siko-wv58m", "fraba-posital-awc58-c2-mt", "waycon-sx")
MODULES = sorted(MODULE_AREAS)
HOSTILE = "<script>alert('x')</script>"


def _fake(n: int, rng: random.Random, tests: int = 30) -> RunSummary:
    """A plausible run: a station, a profile, a serial (some seen several times), a few failing tests."""
    serial = 10_000_000 + rng.randrange(max(n // 4, 1))
    results = []
    for t in range(tests):
        module = MODULES[(t * 7 + n) % len(MODULES)]
        failing = rng.random() < 0.02 * (1 + n % 4) or (n % 4 == 3 and t == n % tests)  # a lab run fails
        outcome = "failed" if failing else "skipped" if rng.random() < 0.1 else "passed"
        message = "expected 0x00000004 in 1017h\nobserved 0x00000000" if outcome == "failed" else ""
        results.append(TestResult(f"suites/{module}.py::test_{t}", MODULE_AREAS[module], outcome,  # type: ignore[arg-type]
                                  "cia", "CiA 301 §7.5.2", message, 0.01))
    day = 1 + n % 28
    return RunSummary(
        kind="accept" if n % 5 else "run",
        started=f"2026-{1 + n % 11:02d}-{day:02d}T{8 + n % 9:02d}:{n % 60:02d}:00+01:00",
        profile_id=PROFILES[n % len(PROFILES)], profile_sha256="ab" * 32, duration_s=3.1,
        identity={"serial number (1018h.4)": f"{serial} (0x{serial:08X})", "revision (1018h.3)": "0x03060208",
                  "device name (1008h)": HOSTILE if n == 3 else "WDGA-MT-CO"},
        settings={"bitrate": "250000 (from station goods-in.toml)"}, station=STATIONS[n % len(STATIONS)],
        operator="J. Meyer", results=results, exit_code=0, device_restored=True, report_dir=f"/srv/reports/run-{n}")


def fill(target: Target, count: int, seed: int = 29, tests: int = 30) -> None:
    """``count`` fake runs, quickly (SQLite without waiting for the disk at each commit)."""
    rng = random.Random(seed)
    with open_db(target) as database:
        if database.dialect == "sqlite":
            database.run("PRAGMA synchronous = OFF")
        for n in range(count):
            records.insert_run(database, _fake(n, rng, tests), f"fake-{seed}-{n}")


class Page:
    def __init__(self, address: str) -> None:
        self.address = address

    def get(self, path: str) -> tuple[int, str]:
        try:
            with urllib.request.urlopen(self.address + path.lstrip("/"), timeout=30) as answer:
                return answer.status, answer.read().decode()
        except urllib.error.HTTPError as error:
            return error.code, error.read().decode()


def _serve(target: Target) -> Iterator[Page]:
    process = subprocess.Popen([sys.executable, "-m", "encoder_conformance", "history", "serve", "--db",
                                str(target), "--listen", "127.0.0.1:0"], cwd=REPO, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        line = process.stdout.readline()
        assert line.startswith("history serve: http://127.0.0.1:"), line + process.stderr.read()
        yield Page(line.split()[2])
    finally:
        process.terminate()
        process.wait(timeout=30)


@pytest.fixture(scope="module")
def history(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("web")
    path = folder / "history.sqlite"
    fill(path, 120)
    report = folder / "reports" / "run-7"  # one run whose report folder this computer reaches
    report.mkdir(parents=True)
    (report / "run-summary.json").write_text("{}", encoding="utf-8")
    (report / "report.html").write_text("<html><body>the report of run 8</body></html>", encoding="utf-8")
    (report / "certificate.html").write_text("<html><body>certificate</body></html>", encoding="utf-8")
    with open_db(path) as database, database.transaction():
        database.run("UPDATE runs SET report_dir = ?, certificate = ? WHERE id = 8",
                     (str(report), str(report / "certificate.html")))
    return path


@pytest.fixture(scope="module")
def page(history) -> Iterator[Page]:
    yield from _serve(history)


def _rows(text: str) -> int:
    return text.split('<table id="runs">', 1)[1].split("</table>", 1)[0].count('<a href="/run/')


def test_the_list_shows_the_newest_runs_a_page_at_a_time(page):
    status, text = page.get("/")
    assert status == 200
    assert "<b>120</b> run(s) match; 1-50 shown, newest first" in text
    assert _rows(text) == 50
    assert "page 1 of 3" in text
    assert 'href="/?page=2"' in text


@pytest.mark.parametrize(("query", "check"), [
    ("station=lab", lambda r: r["station"] == "lab"),
    ("verdict=FAIL&kind=accept", lambda r: r["overall"] == "FAIL" and r["kind"] == "accept"),
    ("profile=siko-wv58m&from=2026-03-01&until=2026-03-31",
     lambda r: r["profile_id"] == "siko-wv58m" and r["started"].startswith("2026-03")),
])
def test_filters_narrow_the_list(page, history, query, check):
    from encoder_conformance.history.db import list_runs

    expected = [r for r in list_runs(history) if check(r)]
    status, text = page.get(f"/?{query}")
    assert status == 200
    assert 0 < len(expected) < 120
    assert f"<b>{len(expected)}</b> run(s) match" in text
    assert _rows(text) == min(len(expected), 50)


@pytest.mark.parametrize(("query", "message"), [
    ("from=yesterday", "from &#39;yesterday&#39;: not a date; give YYYY-MM-DD"),
    ("until=2026-13-01", "until &#39;2026-13-01&#39;: not a date"),
    ("from=2026-05-01&until=2026-04-01", "until &#39;2026-04-01&#39; is before from &#39;2026-05-01&#39;"),
    ("verdict=GOOD", "verdict &#39;GOOD&#39;: not a overall verdict; give one of PASS, PASS WITH WARNINGS, INCOMPLETE, "
                     "FAIL"),
    ("kind=all", "kind &#39;all&#39;: not a run or accept; give one of run, accept"),
    ("page=0", "page &#39;0&#39;: not a page number"),
    ("serial=0xZZ", "serial &#39;0xZZ&#39;: not a number"),
    ("colour=red", "&#39;colour&#39;: not a filter; the filters are serial, station"),
])
def test_a_bad_filter_is_answered_with_a_clear_message(page, query, message):
    status, text = page.get(f"/?{query}")
    assert status == 400
    assert message in text
    assert "Traceback" not in text


def test_a_run_page_shows_identity_areas_failures_settings_and_files(page):
    status, text = page.get("/run/8")
    assert status == 200
    for shown in ("Run 8 (accept)", "0x03060208", "waycon-sx", "lab",
                  "Verdict per area", "expected 0x00000004 in 1017h\nobserved 0x00000000",
                  "250000 (from station goods-in.toml)", 'href="/run/8/files/report.html"',
                  'href="/run/8/files/certificate.html"'):
        assert shown in text, shown
    assert page.get("/run/8/files/report.html") == (200, "<html><body>the report of run 8</body></html>")
    assert page.get("/run/8/files/certificate.html")[0] == 200
    assert "not reachable from this" in page.get("/run/9")[1]  # /srv/reports/run-9 is on the station


@pytest.mark.parametrize("path", ["/run/8/files/..%2F..%2Fhistory.sqlite", "/run/8/files/../../history.sqlite",
                                  "/run/9/files/report.html", "/run/99999", "/serial/123"])
def test_nothing_outside_a_report_folder_is_served(page, path):
    assert page.get(path)[0] == 404


def test_every_value_is_escaped(page):
    status, text = page.get("/run/4")  # run 4's device name is a script
    assert status == 200
    assert HOSTILE not in text
    assert "&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt;" in text
    assert page.get("/?station=" + urllib.parse.quote("<b>x</b>"))[1].count("<b>x</b>") == 0


def test_a_serial_numbers_timeline_and_the_pass_rates(page, history):
    from encoder_conformance.history.db import list_runs

    serial = max({r["serial"] for r in list_runs(history)}, key=lambda s: sum(r["serial"] == s
                                                                              for r in list_runs(history)))
    runs = [r for r in list_runs(history) if r["serial"] == serial]
    status, text = page.get(f"/serial/{serial}")
    assert status == 200
    assert f"{len(runs)} run(s), oldest first" in text
    assert text.count("<circle") == len(runs)
    status, text = page.get("/stats?kind=accept")
    assert status == 200
    assert text.count("<svg") == 2
    for station in STATIONS:
        assert f"<td>{station}</td>" in text


def test_the_page_writes_nothing_and_only_reads(page, history):
    before = hashlib.sha256(history.read_bytes()).hexdigest()
    for path in ("/", "/?verdict=FAIL", "/run/1", "/stats"):
        assert page.get(path)[0] == 200
    request = urllib.request.Request(page.address, data=b"x=1", method="POST")
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(request, timeout=30)
    assert refused.value.code == 405
    assert hashlib.sha256(history.read_bytes()).hexdigest() == before
    assert page.address.startswith("http://127.0.0.1:")


def _timed(page: Page, path: str, times: int = 7) -> float:
    durations = []
    for _ in range(times):
        start = time.perf_counter()
        status, _ = page.get(path)
        durations.append(time.perf_counter() - start)
        assert status == 200, path
    return statistics.median(durations) * 1000


def test_ten_thousand_runs_list_and_filter_in_well_under_a_second(tmp_path):
    """The list and a filter take about 10-30 ms here (the issue asks < 200 ms); asserted with room for a loaded
    CI machine."""
    path = tmp_path / "history.sqlite"
    fill(path, 10_000, tests=20)
    for served in _serve(path):
        figures = {p: _timed(served, p) for p in ("/", "/?station=lab&verdict=FAIL", "/?serial=10000007",
                                                  "/?from=2026-03-01&until=2026-03-31&page=3", "/stats")}
        print("median ms with 10,000 runs:", {p: round(ms, 1) for p, ms in figures.items()})
        assert figures["/"] < 1000
        assert figures["/?station=lab&verdict=FAIL"] < 1000


def _chromium() -> str:
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found is None:
        pytest.skip("no Chromium here (apt-get install chromium; CI installs it)")
    pytest.importorskip("playwright", reason="Playwright is not installed (pip install -e '.[dev]')")
    return found


@pytest.fixture(scope="module")
def browser():
    executable = _chromium()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=executable, args=["--no-sandbox"])
        try:
            yield chromium.new_page(viewport={"width": 1280, "height": 900})
        finally:
            chromium.close()


def _screenshot(tab, name: str) -> None:
    folder = os.environ.get("HISTORY_SCREENSHOTS")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        tab.screenshot(path=str(Path(folder) / name), full_page=True)


def test_in_chromium_the_page_loads_and_filters_narrow_the_list(browser, page):
    browser.goto(page.address)
    assert browser.title() == "Runs - run history"
    assert browser.locator("#runs tr").count() == 51  # the header and 50 runs
    _screenshot(browser, "history-list.png")
    browser.select_option("select[name=station]", "lab")
    browser.select_option("select[name=verdict]", "FAIL")
    browser.click("button[type=submit]")
    browser.wait_for_url("**/?*station=lab*")
    rows = browser.locator("#runs tr").all()[1:]
    assert 0 < len(rows) < 50
    assert all("lab" in row.inner_text() and "FAIL" in row.inner_text() for row in rows)
    _screenshot(browser, "history-list-filtered.png")


def test_in_chromium_a_run_shows_its_failures_and_a_serial_its_timeline(browser, page):
    browser.goto(page.address + "?verdict=FAIL")
    browser.locator("#runs a[href^='/run/']").first.click()
    browser.wait_for_url("**/run/*")
    failures = browser.locator("#failures").inner_text()
    assert "expected 0x00000004 in 1017h" in failures
    assert "observed 0x00000000" in failures
    _screenshot(browser, "history-run.png")
    browser.locator("#identity a[href^='/serial/']").click()
    browser.wait_for_url("**/serial/*")
    assert browser.locator("svg circle").count() >= 1
    _screenshot(browser, "history-timeline.png")
    browser.goto(page.address + "stats")
    assert browser.locator("svg.plot").count() == 2
    _screenshot(browser, "history-pass-rates.png")


def test_in_chromium_a_broken_filter_gives_the_message(browser, page):
    browser.goto(page.address)
    browser.fill("input[name=serial]", "0xZZ")
    browser.click("button[type=submit]")
    assert browser.locator("#message").inner_text() == "serial '0xZZ': not a number; give it in decimal or as 0x-hex"
    assert browser.title() == "Bad filter - run history"
    _screenshot(browser, "history-bad-filter.png")
