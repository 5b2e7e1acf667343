"""At the end of a conformance run: append it to the history, and write an acceptance run's certificate.

Neither may change the run's verdict: a broken, locked, unreachable or refusing history gives one warning line
and the run's exit status stands. The record is written to the spool beside the report folder first
(``history-spool/<run key>.json``, whole or not at all) and deleted after the database's commit, so it waits
there for the next run or ``encoder-conformance history sync`` when the database could not take it; a run killed
in between leaves the file, whose key makes a second sending a no-op. After its own record, a run sends what
earlier runs left waiting for the same history.
"""

from __future__ import annotations

import sys
import uuid
from pathlib import Path

import pytest

from encoder_conformance.history import spool
from encoder_conformance.history.db import OFF, HistoryError, Target, history_path, record_new
from encoder_conformance.history.sync import send_waiting
from encoder_conformance.history.target import target_key
from encoder_conformance.plugin.option_table import pytest_name
from encoder_conformance.plugin.options import settings_of
from encoder_conformance.plugin.run_record import summary_of

OPTION = pytest_name("--history")  # declared in option_table.py


def _target(config: pytest.Config) -> Target | None:
    given = config.getoption(OPTION, default=None)
    if given == OFF:
        return None
    station = settings_of(config).station
    return history_path(given, station.history if station is not None else None)


def _say(config: pytest.Config, text: str, warning: bool = False) -> None:
    """On pytest's terminal, or plain stdout/stderr where there is none (accept runs with -p no:terminal)."""
    if config.pluginmanager.get_plugin("terminalreporter") is not None:
        config.get_terminal_writer().line(text, yellow=warning)
    else:
        print(text, file=sys.stderr if warning else sys.stdout, flush=True)


def record(session: pytest.Session) -> None:
    """Called after run_record.finish: the summary is complete and written."""
    try:
        _record(session.config)
    except Exception as exc:  # a bug here must not turn the device's verdict into the tool's internal error
        _say(session.config, f"history: this run was not recorded ({type(exc).__name__}: {exc}); the verdict "
                             "stands; please report this with the output", warning=True)


def _record(config: pytest.Config) -> None:
    summary = summary_of(config)
    if summary is None or summary.report_dir is None:
        return
    certificate = None
    if summary.kind == "accept":
        try:
            from encoder_conformance.history.certificate import write_certificate  # jinja2: acceptance runs only

            files = write_certificate(summary, Path(summary.report_dir))
        except OSError as exc:
            _say(config, f"certificate: not written ({exc}); make it later with 'encoder-conformance history show "
                         "RUN_ID --certificate'", warning=True)
        else:
            certificate = str(files.html)
            _say(config, f"certificate: {files.pdf or files.html}" + (f" ({files.pdf_note})" if files.pdf_note
                                                                      else ""))
    try:
        target = _target(config)
    except HistoryError as exc:
        _say(config, f"history: this run was not recorded: {exc}; the verdict stands (give {OPTION} PATH or URL)",
             warning=True)
        return
    if target is None:
        return
    key = str(uuid.uuid4())
    folder = spool.folder_for(Path(summary.report_dir))
    try:
        spooled: Path | None = spool.put(folder, key, target_key(target), summary, certificate)
        unspooled = ""
    except OSError as exc:
        spooled, unspooled = None, f"{folder}: {exc.strerror or exc}"
    try:
        run_id, _ = record_new(summary, target, key, certificate)
    except HistoryError as exc:
        if spooled is not None:
            _say(config, f"history: this run was not recorded: {exc}; the verdict stands; the record waits in "
                         f"{spooled} for the next run or 'encoder-conformance history sync'", warning=True)
        else:
            _say(config, f"history: this run was not recorded: {exc}; the verdict stands (fix or move the file, "
                         f"or give {OPTION} PATH; the spool could not keep it either: {unspooled})", warning=True)
        return
    if spooled is not None:
        spool.remove(spooled)
    _say(config, f"history: run {run_id} recorded in {target}")
    _send_earlier(config, target, folder)


def _send_earlier(config: pytest.Config, target: Target, folder: Path) -> None:
    report = send_waiting(target, folder)
    if report.sent or report.already:
        _say(config, f"history: {len(report.sent)} earlier run(s) sent from {folder}"
                     + (f" ({len(report.already)} were there already)" if report.already else ""))
    if report.error:
        _say(config, f"history: {report.left} earlier run(s) still wait in {folder}: {report.error}", warning=True)
