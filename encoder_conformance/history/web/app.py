"""The history page's routes (Starlette): the list with filters, one run, one serial number's timeline, the pass
rates, and the files of a run's report folder.

Starlette because it is a small, maintained toolkit (routing, query strings, responses; no ORM, no templates of
its own) on the ASGI server uvicorn, which parses HTTP robustly where the standard library's http.server says it
is not meant for a network. Read-only: every request opens the history read-only (SQLite ``mode=ro``, a
PostgreSQL session with ``default_transaction_read_only``), only GET and HEAD are routed, and a file is served
only from inside a recorded report folder that holds a run-summary.json. A bad filter is a 400 page with its
message; an unreadable history a 503 with the reason; never a traceback.
"""

from __future__ import annotations

import json
from pathlib import Path

from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import FileResponse, HTMLResponse, Response
from starlette.routing import Route

from encoder_conformance.errors import HistoryError, UsageError
from encoder_conformance.history.backend import open_db
from encoder_conformance.history.db import stored
from encoder_conformance.history.target import Target
from encoder_conformance.history.web import pages, queries
from encoder_conformance.history.web.params import KINDS, VERDICTS, parse
from encoder_conformance.history.web.plot import group_plot, timeline_plot
from encoder_conformance.run_summary import AREAS, SUMMARY_FILE

PAGE_HEADERS = {"Content-Security-Policy": "default-src 'none'; style-src 'unsafe-inline'; img-src 'self' data:; "
                                          "form-action 'self'; frame-ancestors 'none'",
                "X-Content-Type-Options": "nosniff", "Referrer-Policy": "no-referrer", "Cache-Control": "no-store"}
#: a report's own files may run their scripts, in a sandbox of their own (no access to this page's origin)
FILE_HEADERS = {"Content-Security-Policy": "sandbox allow-scripts allow-popups", "X-Content-Type-Options": "nosniff"}
REPORT = "report.html"
CERTIFICATES = ("certificate.html", "certificate.pdf")


def make_app(target: Target) -> Starlette:
    where = str(target)

    def page(name: str, status: int = 200, **values: object) -> HTMLResponse:
        return HTMLResponse(pages.render(name, where=where, **values), status_code=status, headers=PAGE_HEADERS)

    def read():
        return open_db(target, create=False, readonly=True)

    def runs(request: Request) -> Response:
        filters, number = parse(request.query_params.multi_items())
        with read() as db:
            total, rows = queries.runs_page(db, filters, number)
            choices = queries.choices(db)
        count = max(1, -(-total // queries.PAGE_SIZE))
        first = (number - 1) * queries.PAGE_SIZE + 1
        return page("list", f=filters, rows=rows, total=total, page=number, pages=count, choices=choices,
                    kinds=KINDS, verdicts=VERDICTS, first=first, last=first + len(rows) - 1)

    def run(request: Request) -> Response:
        with read() as db:
            row = queries.run_row(db, _run_id(request))
            if row is None:
                raise HTTPException(404, f"no run {request.path_params['run_id']} in the history")
            full = stored(db, row)
        restored = {None: "nothing to restore", 1: "yes, as found", 0: "NO (see the report)"}.get(
            row["device_restored"], "-")
        failures = [r for r in full.results if r["outcome"] in ("failed", "error")]
        report = _file_in_report(row, REPORT)
        certificate = _certificate(row)
        return page("run", r=row, areas=full.areas, results=full.results, failures=failures,
                    identity=json.loads(row["identity"]), settings=json.loads(row["settings"]), restored=restored,
                    report_link=f"/run/{row['id']}/files/{REPORT}" if report else None,
                    certificate_link=f"/run/{row['id']}/files/{certificate.name}" if certificate else None)

    def serial(request: Request) -> Response:
        number = request.path_params["serial"]
        with read() as db:
            rows, areas = queries.timeline(db, number)
        if not rows:
            raise HTTPException(404, f"no run of serial number {number} in the history")
        seen = {area for run_areas in areas.values() for area in run_areas}
        names = [a for a in AREAS if a in seen] + sorted(seen - set(AREAS))
        return page("timeline", serial=number, runs=rows, areas=areas, area_names=names, plot=timeline_plot(rows))

    def stats(request: Request) -> Response:
        filters, _ = parse(request.query_params.multi_items())
        with read() as db:
            sections = [("station", queries.groups(db, filters, "station")),
                        ("profile", queries.groups(db, filters, "profile_id"))]
        plots = [group_plot(groups, f"pass rate and failing areas per {title}") for title, groups in sections]
        return page("stats", f=filters, sections=sections, plots=plots)

    def report_file(request: Request) -> Response:
        with read() as db:
            row = queries.run_row(db, _run_id(request))
        name = request.path_params["name"]
        path = None
        if row is not None:
            recorded = _certificate(row) if name in CERTIFICATES else None
            path = recorded if recorded is not None and recorded.name == name else _file_in_report(row, name)
        if path is None:
            raise HTTPException(404, f"{name} of run {request.path_params['run_id']} is not reachable from here")
        return FileResponse(path, headers=FILE_HEADERS)

    def bad_filter(request: Request, exc: Exception) -> Response:
        return page("error", status=400, title="Bad filter", message=str(exc))

    def unavailable(request: Request, exc: Exception) -> Response:
        return page("error", status=503, title="The history cannot be read", message=str(exc))

    def not_found(request: Request, exc: Exception) -> Response:
        detail = exc.detail if isinstance(exc, HTTPException) else "not found"
        status = exc.status_code if isinstance(exc, HTTPException) else 404
        return page("error", status=status, title="Not found" if status == 404 else "Not allowed", message=detail)

    routes = [Route("/", runs), Route("/run/{run_id}", run), Route("/run/{run_id}/files/{name:path}", report_file),
              Route("/serial/{serial}", serial), Route("/stats", stats)]
    return Starlette(routes=routes, exception_handlers={UsageError: bad_filter, HistoryError: unavailable,
                                                        HTTPException: not_found})


def _run_id(request: Request) -> int:
    text = request.path_params["run_id"]
    if not text.isdigit() or len(text) > 18:
        raise UsageError(f"run {text[:40]!r}: not a run id; the list's id column has them")
    return int(text)


def _report_folder(row: dict[str, object]) -> Path | None:
    """The run's report folder, where this computer reaches it and it is one (it holds run-summary.json)."""
    if not row.get("report_dir"):
        return None
    folder = Path(str(row["report_dir"]))
    try:
        return folder.resolve() if (folder / SUMMARY_FILE).is_file() else None
    except OSError:
        return None


def _file_in_report(row: dict[str, object], name: str) -> Path | None:
    folder = _report_folder(row)
    if folder is None:
        return None
    path = (folder / name).resolve()
    return path if path.is_relative_to(folder) and path.is_file() else None


def _certificate(row: dict[str, object]) -> Path | None:
    """The recorded certificate where this computer reaches it (only a file named as a certificate is)."""
    if not row.get("certificate"):
        return None
    path = Path(str(row["certificate"]))
    return path if path.name in CERTIFICATES and path.is_file() else None
