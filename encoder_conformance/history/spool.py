"""The spool: a run's history record on the station's disk until the database has it.

Every run writes its record here first (``history-spool/<run key>.json`` beside its report folder), then sends
it, then deletes the file: only after the database's commit. So a database that is unreachable or refuses the
write loses nothing (the file waits for the next run or ``history sync``), and a run killed at any moment leaves
either no file, or a whole file whose record the database has not, or has once (its key is UNIQUE there).

A file is written whole or not at all: into a hidden temporary file, flushed to the disk, then renamed over
(``os.replace`` is atomic); a killed writer leaves at most a ``.*.tmp`` file, which nothing reads. Each file
names the history it was meant for (without password): a record is sent only there.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path

from encoder_conformance.run_summary import RunSummary

FOLDER_NAME = "history-spool"
FORMAT = 1


@dataclass(frozen=True)
class Waiting:
    """One record in the spool."""

    path: Path
    key: str
    history: str  # target.target_key of the history it is meant for
    summary: RunSummary
    certificate: str | None


def folder_for(report_dir: Path) -> Path:
    """The spool of runs whose report folders are beside ``report_dir`` (reports/history-spool)."""
    return report_dir.absolute().parent / FOLDER_NAME


def put(folder: Path, key: str, history: str, summary: RunSummary, certificate: str | None = None) -> Path:
    """Write one record whole (raises OSError)."""
    folder.mkdir(parents=True, exist_ok=True)
    data = {"format": FORMAT, "run_key": key, "history": history, "certificate": certificate,
            "summary": json.loads(summary.to_json())}
    final = folder / f"{key}.json"
    temporary = folder / f".{key}.json.tmp"
    with open(temporary, "w", encoding="utf-8") as out:
        out.write(json.dumps(data, indent=1))
        out.flush()
        os.fsync(out.fileno())
    os.replace(temporary, final)
    _sync_folder(folder)
    return final


def _sync_folder(folder: Path) -> None:
    """The rename itself on the disk (POSIX; elsewhere a no-op)."""
    with suppress(OSError, AttributeError):
        handle = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(handle)
        finally:
            os.close(handle)


def read(path: Path) -> Waiting:
    """One record (raises OSError, ValueError, KeyError, TypeError for a file that is not one)."""
    data = json.loads(path.read_text(encoding="utf-8"))
    if data.get("format") != FORMAT:
        raise ValueError(f"spool format {data.get('format')!r}, this suite reads {FORMAT}")
    summary = RunSummary.from_json(json.dumps(data["summary"]))
    return Waiting(path, str(data["run_key"]), str(data["history"]), summary, data.get("certificate"))


def waiting(folder: Path) -> Iterator[Path]:
    """The records in ``folder``, oldest first (not the temporary files of a writer)."""
    if not folder.is_dir():
        return iter(())
    files = [p for p in folder.glob("*.json") if not p.name.startswith(".")]
    return iter(sorted(files, key=_age))


def _age(path: Path) -> tuple[float, str]:
    try:
        return path.stat().st_mtime, path.name
    except OSError:
        return 0.0, path.name


def remove(path: Path) -> None:
    """After the database's commit; another sender may have removed it first."""
    with suppress(FileNotFoundError):
        path.unlink()
