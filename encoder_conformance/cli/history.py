"""``encoder-conformance history list | show | export | compare | sync | serve | upgrade``: what the history
database holds (an SQLite file or a PostgreSQL URL), the records waiting in the spool, and the history page.

Light at start-up (the command line builds every parser): the database drivers, the views and the web stack
load only when a history command runs; the work is done in encoder_conformance/history/. Every usage error (no
database, unknown run, bad date, unreadable station file) is one line naming the option and the fix, exit code 4.
"""

from __future__ import annotations

import argparse
import os
import sys
from datetime import UTC, datetime
from pathlib import Path

from encoder_conformance.errors import UsageError
from encoder_conformance.exit_codes import RunExit


def parse_since(text: str) -> str:
    """--since: a date (YYYY-MM-DD, local midnight) or an ISO date-time (local time unless it has an offset),
    as UTC ISO text to compare with the history's started_utc."""
    try:
        moment = datetime.fromisoformat(text.strip())
    except ValueError:
        raise UsageError(f"--since {text!r}: not a date; give YYYY-MM-DD or an ISO date-time such as "
                         "2026-11-26T08:00") from None
    return (moment if moment.tzinfo else moment.astimezone()).astimezone(UTC).isoformat(timespec="seconds")


def _serial(text: str | None) -> str | None:
    """--serial in decimal (as stored) or 0x-hex (as a configuration tool may show 1018h.4)."""
    if text is None or not text.lower().startswith("0x"):
        return text
    try:
        return str(int(text, 16))
    except ValueError:
        raise UsageError(f"--serial {text!r}: not a number; give it in decimal or as 0x-hex") from None


def _run_id(text: str, what: str) -> int:
    if not text.strip().isdigit():
        raise UsageError(f"{what} {text!r}: not a run id; give the number 'history list' shows in its id column")
    return int(text)


def _station(args: argparse.Namespace):  # -> Station | None (imported lazily)
    from encoder_conformance.config.station import StationError, load_station

    if args.station is None:
        return None
    try:
        return load_station(Path(args.station))
    except StationError as exc:
        raise UsageError(str(exc).replace("\n", " ")) from None


def _db(args: argparse.Namespace, must_exist: bool = True):  # -> db.Target (imported lazily)
    from encoder_conformance.history.db import HistoryError, history_path, path_exists

    station = _station(args) if args.db is None else None
    station_history = station.history if station is not None else None
    try:
        path = history_path(args.db, station_history)
    except HistoryError as exc:
        raise UsageError(f"--db {exc}") from None
    if must_exist and not path_exists(path):
        source = "--db" if args.db else "--station's history" if station_history else "the history database"
        raise UsageError(f"{source} {path}: no history database there; give --db PATH (or --station FILE) with "
                         "the file the runs were recorded in")
    return path


def _filters(args: argparse.Namespace):  # -> db.Filters (imported lazily)
    from encoder_conformance.history.db import Filters

    return Filters(serial=_serial(args.serial), profile=args.profile, kind=args.kind,
                   since_utc=parse_since(args.since) if args.since else None)


def _stored(path, text: str, what: str):  # noqa: ANN001 - db.Target  # -> db.StoredRun (imported lazily)
    from encoder_conformance.history.db import get_run

    run = get_run(path, _run_id(text, what))
    if run is None:
        raise UsageError(f"{what} {text}: no such run in {path}; 'history list' shows the ids")
    return run


def _list(args: argparse.Namespace) -> int:
    from encoder_conformance.history.db import list_runs
    from encoder_conformance.history.views import run_table

    runs = list_runs(_db(args), _filters(args))
    print(run_table(runs) if runs else "no run in the history matches")
    return 0


def _show(args: argparse.Namespace) -> int:
    from encoder_conformance.history.certificate import write_certificate
    from encoder_conformance.history.db import note_certificate
    from encoder_conformance.history.views import show

    path = _db(args)
    stored = _stored(path, args.run_id, "RUN_ID")
    written = None
    if args.certificate:
        folder = Path(args.output) if args.output else Path(stored.run["report_dir"] or ".")
        if not folder.is_dir():
            folder = Path.cwd()  # the run's report folder is gone (a temporary run): here instead
        try:
            files = write_certificate(stored.summary(), folder)
        except OSError as exc:
            raise UsageError(f"--certificate: cannot write into {folder}: {exc.strerror}; give -o FOLDER") from None
        note_certificate(path, stored.run["id"], files.html)
        written = str(files.html) + (f" and {files.pdf}" if files.pdf else f" ({files.pdf_note})")
    print(show(stored, written))
    return 0


def _export(args: argparse.Namespace) -> int:
    from encoder_conformance.history.db import load_runs
    from encoder_conformance.history.views import export_csv, export_json

    runs = load_runs(_db(args), _filters(args))
    text = export_csv(runs) if args.format == "csv" else export_json(runs)
    if args.output is None:
        sys.stdout.write(text)
        return 0
    try:
        Path(args.output).write_text(text, encoding="utf-8", newline="")
    except OSError as exc:
        raise UsageError(f"-o {args.output}: cannot write it: {exc.strerror}; give a writable file") from None
    print(f"wrote {len(runs)} run(s) to {args.output}", file=sys.stderr)
    return 0


def _compare(args: argparse.Namespace) -> int:
    from encoder_conformance.history.views import compare

    path = _db(args)
    print(compare(_stored(path, args.run_a, "RUN_A"), _stored(path, args.run_b, "RUN_B")))
    return 0


def _spool_folder(args: argparse.Namespace) -> Path:
    from encoder_conformance.history.spool import FOLDER_NAME
    from encoder_conformance.paths import default_reports_dir

    if args.spool:
        return Path(args.spool)
    station = _station(args)
    reports = station.reports if station is not None and station.reports is not None else default_reports_dir()
    return Path(reports) / FOLDER_NAME


def _sync(args: argparse.Namespace) -> int:
    from encoder_conformance.history.sync import send_waiting

    target, folder = _db(args, must_exist=False), _spool_folder(args)
    report = send_waiting(target, folder)
    print(report.text(target, folder))
    return RunExit.USAGE_ERROR if report.error else 0


def _upgrade(args: argparse.Namespace) -> int:
    from encoder_conformance.history.backend import upgrade

    target = _db(args)
    found, now = upgrade(target)
    print(f"{target}: schema {now}" + (f" (upgraded from {found})" if found != now else " (already current)"))
    return 0


def parse_listen(text: str) -> tuple[str, int]:
    """--listen HOST:PORT ([::1]:8600 for an IPv6 address)."""
    host, _, port = text.rpartition(":")
    host = host.strip("[]")
    if not host or not port.isdigit() or int(port) > 65535:
        raise UsageError(f"--listen {text!r}: give HOST:PORT, such as 127.0.0.1:8600")
    return host, int(port)


def _serve(args: argparse.Namespace) -> int:
    from encoder_conformance.history.web.server import serve

    host, port = parse_listen(args.listen)
    return serve(_db(args), host, port)


def _run(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.history.db import HistoryError

    try:
        return args.history_func(args)
    except BrokenPipeError:  # 'history list | head': the reader has all it wanted
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - Python flushes stdout at exit: not into the closed pipe
        return 0
    except UsageError as exc:
        print(f"history {args.history_command}: {exc}", file=sys.stderr)
    except HistoryError as exc:
        hint = "" if args.history_command in ("sync", "serve", "upgrade") else \
            "; give --db PATH with a history database the runs wrote"
        print(f"history {args.history_command}: {exc}{hint}", file=sys.stderr)
    return RunExit.USAGE_ERROR


def _where(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--db", metavar="PATH|URL", help="the history database: an SQLite file or "
                        "postgresql://user@host/database (default: the station file's history, else "
                        "$ENCODER_CONFORMANCE_HISTORY, else reports/history.sqlite)")
    parser.add_argument("--station", metavar="FILE", help="station file whose 'history' names the database")


def _selection(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--serial", help="only this serial number (1018h.4, decimal or 0x-hex)")
    parser.add_argument("--since", metavar="DATE", help="only runs started on or after DATE (YYYY-MM-DD or ISO "
                        "date-time, local time)")
    parser.add_argument("--profile", help="only runs of this profile id")
    parser.add_argument("--kind", choices=["run", "accept"], help="only full runs or only acceptance checks")
    _where(parser)


def add_history_parser(sub, parser_class: type[argparse.ArgumentParser]) -> None:  # noqa: ANN001 - subparsers
    history = sub.add_parser("history", help="the recorded runs: list, show, export, compare, sync, serve, upgrade "
                                             "(SQLite or PostgreSQL history)")
    hsub = history.add_subparsers(dest="history_command", required=True, parser_class=parser_class)
    listing = hsub.add_parser("list", help="one line per recorded run, oldest first")
    _selection(listing)
    listing.set_defaults(history_func=_list)
    show = hsub.add_parser("show", help="one run: device, settings, areas, failures, report folder, certificate")
    show.add_argument("run_id", metavar="RUN_ID")
    show.add_argument("--certificate", action="store_true",
                      help="write the run's one-page certificate (certificate.html, and .pdf where WeasyPrint works)")
    show.add_argument("-o", "--output", metavar="FOLDER",
                      help="folder for the certificate (default: the run's report folder)")
    _where(show)
    show.set_defaults(history_func=_show)
    export = hsub.add_parser("export", help="the selected runs as CSV (one row per run) or JSON (runs in full)")
    export.add_argument("--format", choices=["csv", "json"], default="csv")
    export.add_argument("-o", "--output", metavar="FILE", help="write to FILE (default: standard output)")
    _selection(export)
    export.set_defaults(history_func=_export)
    compare = hsub.add_parser("compare", help="two runs (of one serial number): area verdicts and test outcomes "
                                              "that changed")
    compare.add_argument("run_a", metavar="RUN_A")
    compare.add_argument("run_b", metavar="RUN_B")
    _where(compare)
    compare.set_defaults(history_func=_compare)
    sync = hsub.add_parser("sync", help="send the records that wait in the spool (the database was unreachable or "
                                        "refused them) to the history, each once")
    sync.add_argument("--spool", metavar="FOLDER", help="the spool folder (default: history-spool in the station "
                      "file's reports, else reports/history-spool)")
    _where(sync)
    sync.set_defaults(history_func=_sync)
    serve = hsub.add_parser("serve", help="a read-only web page of the history for the quality office: runs with "
                                          "filters, one run, a serial number's timeline, pass rates per station "
                                          "and profile")
    serve.add_argument("--listen", metavar="HOST:PORT", default="127.0.0.1:8600",
                       help="where the page listens (default 127.0.0.1:8600, this computer only; 0.0.0.0:8600 for "
                            "the network)")
    _where(serve)
    serve.set_defaults(history_func=_serve)
    upgrade = hsub.add_parser("upgrade", help="bring the history's schema to this version of the suite (a run does "
                                              "it by itself where its database user may)")
    _where(upgrade)
    upgrade.set_defaults(history_func=_upgrade)
    history.set_defaults(func=_run)
