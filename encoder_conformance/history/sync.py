"""Send what waits in the spool: by every run after its own record, and by ``history sync``.

Each record goes in its own transaction under its run's key, and its file is deleted after the commit: a record
the database has already (sent by a parallel run, or by one killed before it could delete the file) is counted
as such and its file deleted; none is recorded twice. Records meant for another history stay where they are.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from encoder_conformance.errors import HistoryError
from encoder_conformance.history import records, spool
from encoder_conformance.history.backend import open_db
from encoder_conformance.history.target import Target, target_key


@dataclass
class SyncReport:
    sent: list[int] = field(default_factory=list)  # ids of the runs recorded now
    already: list[int] = field(default_factory=list)  # ids of records the history had (files deleted)
    elsewhere: dict[str, int] = field(default_factory=dict)  # records for other histories: history -> count
    unreadable: list[str] = field(default_factory=list)  # "file: why"
    error: str | None = None  # the database failed: the rest waits
    left: int = 0  # records of this history still waiting after an error

    def text(self, target: Target, folder: Path) -> str:
        """What ``history sync`` prints."""
        lines = [f"sent {len(self.sent)} run(s) to {target}" + (f" (ids {', '.join(map(str, self.sent))})"
                                                              if self.sent else "")]
        if self.already:
            lines.append(f"{len(self.already)} record(s) were there already (ids "
                         f"{', '.join(map(str, self.already))}): not recorded again, removed from the spool")
        if self.error:
            lines.append(f"stopped: {self.error}; {self.left} record(s) still wait in {folder}")
        for history, count in sorted(self.elsewhere.items()):
            lines.append(f"{count} record(s) in {folder} wait for another history: {history} (history sync --db "
                         "with that one)")
        lines += [f"not a spool record, left in place: {problem}" for problem in self.unreadable]
        return "\n".join(lines)


def send_waiting(target: Target, folder: Path, busy_timeout_s: float = 10.0) -> SyncReport:
    """Send every record in ``folder`` that is meant for ``target``; never raises (the report says what)."""
    report = SyncReport()
    mine = []
    for path in spool.waiting(folder):
        try:
            record = spool.read(path)
        except FileNotFoundError:
            continue  # sent and removed by a parallel run meanwhile
        except (OSError, ValueError, KeyError, TypeError) as exc:
            report.unreadable.append(f"{path}: {type(exc).__name__}: {exc}")
            continue
        if record.history == target_key(target):
            mine.append(record)
        else:
            report.elsewhere[record.history] = report.elsewhere.get(record.history, 0) + 1
    if not mine:
        return report
    report.left = len(mine)
    try:
        with open_db(target, busy_timeout_s=busy_timeout_s) as db:
            for n, record in enumerate(mine):
                report.left = len(mine) - n
                run_id, new = records.insert_run(db, record.summary, record.key, record.certificate)
                spool.remove(record.path)
                (report.sent if new else report.already).append(run_id)
            report.left = 0
    except HistoryError as exc:
        report.error = str(exc)
    return report
