"""At the end of a conformance run: append it to the history, and write an acceptance run's certificate.

Neither may change the run's verdict: a broken, locked or unwritable history gives one warning line
and the run's exit status stands (the run-summary.json in the report folder still holds everything).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from encoder_conformance.history.certificate import write_certificate
from encoder_conformance.history.db import OFF, HistoryError, history_path, note_certificate, record_run
from encoder_conformance.plugin.options import settings_of
from encoder_conformance.plugin.run_record import summary_of

OPTION = "--history"  # declared in option_table.py


def _db_path(config: pytest.Config) -> Path | None:
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
            files = write_certificate(summary, Path(summary.report_dir))
        except OSError as exc:
            _say(config, f"certificate: not written ({exc}); make it later with 'encoder-conformance history show "
                         "RUN_ID --certificate'", warning=True)
        else:
            certificate = files.html
            _say(config, f"certificate: {files.pdf or files.html}" + (f" ({files.pdf_note})" if files.pdf_note
                                                                      else ""))
    db_path = _db_path(config)
    if db_path is None:
        return
    try:
        run_id = record_run(summary, db_path)
        if certificate is not None:
            note_certificate(db_path, run_id, certificate)
    except HistoryError as exc:
        _say(config, f"history: this run was not recorded: {exc}; the verdict stands (fix or move the file, or "
                     f"give {OPTION} PATH)", warning=True)
        return
    _say(config, f"history: run {run_id} recorded in {db_path}")
