"""What ``history`` prints: the run table, one run in full, an export (CSV / JSON), two runs compared.

Plain text for a terminal and a log; each function returns the text so tests read it without a console.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Sequence
from datetime import datetime

from encoder_conformance.history.db import StoredRun
from encoder_conformance.history.dbapi import Row

LIST_COLUMNS = (("id", "id"), ("date", "started"), ("kind", "kind"), ("profile", "profile_id"),
                ("serial", "serial"), ("revision", "revision"), ("verdict", "overall"), ("station", "station"),
                ("operator", "operator"))
#: runs columns that go into an export as they are (identity and settings are JSON objects of their own)
EXPORT_COLUMNS = ("id", "kind", "started", "duration_s", "profile_id", "profile_sha256", "serial", "revision",
                  "vendor_id", "product_code", "device_name", "overall", "could_not_test", "station", "operator",
                  "report_dir", "exit_code", "device_restored", "certificate")


def _date(started: str) -> str:
    try:
        return datetime.fromisoformat(started).strftime("%Y-%m-%d %H:%M")
    except ValueError:
        return started


def table(rows: Sequence[Sequence[str]]) -> str:
    """Left-aligned columns as wide as their widest cell (no library: a dozen lines, no extra dependency)."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip() for row in rows)


def run_table(runs: Sequence[Row]) -> str:
    rows = [[title for title, _ in LIST_COLUMNS]]
    for run in runs:
        rows.append([_date(run[c]) if c == "started" else str(run[c] if run[c] is not None else "-")
                     for _, c in LIST_COLUMNS])
    return table(rows)


def _restored(value: int | None) -> str:
    return {None: "nothing to restore", 1: "yes, as found", 0: "NO (see the report)"}[value]


def show(stored: StoredRun, certificate: str | None) -> str:
    run = stored.run
    identity = json.loads(run["identity"])
    lines = [f"run {run['id']} ({run['kind']}), {run['started']}, {run['duration_s'] or 0:.1f} s",
             f"verdict: {run['overall']}" + (f" (could not test: {run['could_not_test']})"
                                             if run["could_not_test"] else ""),
             f"profile: {run['profile_id']} sha256 {run['profile_sha256']}",
             f"station: {run['station'] or '-'}, operator: {run['operator'] or '-'}",
             f"exit code: {run['exit_code']}, device given back: {_restored(run['device_restored'])}",
             "device:"]
    lines += [f"  {key}: {value}" for key, value in identity.items()] or ["  not read"]
    lines.append("settings:")
    lines += [f"  {key}: {value}" for key, value in json.loads(run["settings"]).items()]
    lines.append("areas:")
    rows = [["area", "verdict", "passed", "failed", "warnings", "skipped"]]
    rows += [[a["area"], a["verdict"], *(str(a[k]) for k in ("passed", "failed", "warnings", "skipped"))]
             for a in stored.areas]
    lines += ["  " + line for line in table(rows).splitlines()]
    failures = [r for r in stored.results if r["outcome"] in ("failed", "error")]
    lines.append(f"failures: {len(failures) or 'none'}")
    for result in failures:
        message = result["message"].strip().splitlines()
        lines.append(f"  {result['nodeid']}: {message[0] if message else result['outcome']}")
    lines.append(f"report folder: {run['report_dir'] or '-'}")
    lines.append(f"certificate: {certificate or run['certificate'] or 'none yet (history show ID --certificate)'}")
    return "\n".join(lines)


def _areas_text(areas: Sequence[Row]) -> str:
    return "; ".join(f"{a['area']}={a['verdict']}" for a in areas)


def export_csv(runs: Sequence[StoredRun]) -> str:
    """One row per run; the areas in one column ("identity=PASS; SDO=FAIL")."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([*EXPORT_COLUMNS, "areas"])
    for stored in runs:
        writer.writerow([*(stored.run[c] for c in EXPORT_COLUMNS), _areas_text(stored.areas)])
    return out.getvalue()


def _without_run_id(row: Row) -> dict[str, object]:
    return {key: value for key, value in dict(row).items() if key != "run_id"}


def export_json(runs: Sequence[StoredRun]) -> str:
    """Every run in full: its columns, identity, settings, areas and each test's result."""
    data = []
    for stored in runs:
        run = {c: stored.run[c] for c in EXPORT_COLUMNS}
        run["identity"] = json.loads(stored.run["identity"])
        run["settings"] = json.loads(stored.run["settings"])
        run["areas"] = [_without_run_id(a) for a in stored.areas]
        run["results"] = [_without_run_id(r) for r in stored.results]
        data.append(run)
    return json.dumps(data, indent=1) + "\n"


def compare(a: StoredRun, b: StoredRun) -> str:
    """Area verdicts and test outcomes that changed from run A to run B."""
    ra, rb = a.run, b.run
    lines = [f"A: run {ra['id']} ({ra['kind']}) {_date(ra['started'])} serial {ra['serial'] or '-'} "
             f"{ra['profile_id']} {ra['overall']}",
             f"B: run {rb['id']} ({rb['kind']}) {_date(rb['started'])} serial {rb['serial'] or '-'} "
             f"{rb['profile_id']} {rb['overall']}"]
    if ra["serial"] != rb["serial"]:
        lines.append(f"note: not the same device (serial {ra['serial'] or '-'} vs {rb['serial'] or '-'}): "
                     "compare is meant for two runs of one serial number")
    if ra["profile_sha256"] != rb["profile_sha256"]:
        lines.append("note: the profiles differ (id or sha256): a changed expectation can change a verdict")
    areas_a = {x["area"]: x["verdict"] for x in a.areas}
    areas_b = {x["area"]: x["verdict"] for x in b.areas}
    changed = [(area, areas_a.get(area, "-"), areas_b.get(area, "-"))
               for area in [*areas_a, *(x for x in areas_b if x not in areas_a)]
               if areas_a.get(area) != areas_b.get(area)]
    lines.append(f"areas: {len(changed)} changed, {len(set(areas_a) | set(areas_b)) - len(changed)} unchanged")
    lines += [f"  {area}: {old} -> {new}" for area, old, new in changed]
    tests_a = {r["nodeid"]: r for r in a.results}
    tests_b = {r["nodeid"]: r for r in b.results}
    both = [n for n in tests_a if n in tests_b]
    moved = [n for n in both if tests_a[n]["outcome"] != tests_b[n]["outcome"]]
    only_a, only_b = len(tests_a) - len(both), len(tests_b) - len(both)
    lines.append(f"tests: {len(moved)} of {len(both)} run in both changed outcome"
                 + (f"; {only_a} only in A, {only_b} only in B (another selection)" if only_a or only_b else ""))
    for nodeid in moved:
        new = tests_b[nodeid]
        why = new["message"].strip().splitlines()[0] if new["message"].strip() else ""
        lines.append(f"  {nodeid}: {tests_a[nodeid]['outcome']} -> {new['outcome']}"
                     + (f" ({why[:160]})" if why and new["outcome"] != "passed" else ""))
    return "\n".join(lines)
