"""The page's filters, read from the query string: a filter it cannot use is a UsageError whose message says
which and what to give (the page answers it with 400 and that message, never a traceback)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, fields
from datetime import UTC, datetime, timedelta
from urllib.parse import urlencode

from encoder_conformance.errors import UsageError

VERDICTS = ("PASS", "PASS WITH WARNINGS", "INCOMPLETE", "FAIL", "COULD NOT TEST", "INTERNAL ERROR", "NOT RUN")
KINDS = ("run", "accept")
MAX_TEXT = 200
#: query parameter -> what it selects (the page's form uses these names)
NAMES = {"serial": "serial number", "station": "station", "profile": "profile id", "kind": "run or accept",
         "verdict": "overall verdict", "from": "first day", "until": "last day", "page": "page"}


@dataclass(frozen=True)
class PageFilters:
    """What the list (and the pass rates) select; None selects everything. Dates in UTC ISO text."""

    serial: str | None = None
    station: str | None = None
    profile: str | None = None
    kind: str | None = None
    verdict: str | None = None
    since_utc: str | None = None  # started_utc >= this
    before_utc: str | None = None  # started_utc < this
    given_from: str | None = None  # as typed, to show them again in the form
    given_until: str | None = None

    def where(self, prefix: str = "") -> tuple[str, list[str]]:
        """The WHERE clause (``prefix``: the runs table's alias and a dot) and its values."""
        clauses, values = [], []
        for column, value in (("serial", self.serial), ("station", self.station), ("profile_id", self.profile),
                              ("kind", self.kind), ("overall", self.verdict)):
            if value is not None:
                clauses.append(f"{prefix}{column} = ?")
                values.append(value)
        if self.since_utc is not None:
            clauses.append(f"{prefix}started_utc >= ?")
            values.append(self.since_utc)
        if self.before_utc is not None:
            clauses.append(f"{prefix}started_utc < ?")
            values.append(self.before_utc)
        return (f"WHERE {' AND '.join(clauses)}" if clauses else ""), values

    def query(self, **extra: object) -> str:
        """The query string that selects the same again (for links: pages, the pass rates)."""
        pairs = [(name, value) for name, value in (
            ("serial", self.serial), ("station", self.station), ("profile", self.profile), ("kind", self.kind),
            ("verdict", self.verdict), ("from", self.given_from), ("until", self.given_until)) if value]
        pairs += [(k, str(v)) for k, v in extra.items() if v is not None]
        return urlencode(pairs)

    @property
    def any(self) -> bool:
        return any(getattr(self, f.name) is not None for f in fields(self))


def _text(name: str, value: str) -> str:
    if len(value) > MAX_TEXT or any(ord(c) < 32 for c in value):
        raise UsageError(f"{name} {value[:40]!r}: not a {NAMES[name]}; give at most {MAX_TEXT} printable characters")
    return value


def _serial(value: str) -> str:
    if value.lower().startswith("0x"):
        try:
            return str(int(value, 16))
        except ValueError:
            raise UsageError(f"serial {value!r}: not a number; give it in decimal or as 0x-hex") from None
    return _text("serial", value)


def _moment(name: str, value: str) -> tuple[datetime, bool]:
    """A date (local midnight) or an ISO date-time (local time unless it has an offset); True for a date."""
    try:
        moment = datetime.fromisoformat(value)
    except ValueError:
        raise UsageError(f"{name} {value[:40]!r}: not a date; give YYYY-MM-DD (or an ISO date-time such as "
                         "2026-11-26T08:00)") from None
    return (moment if moment.tzinfo else moment.astimezone()), len(value) <= 10


def _utc(moment: datetime) -> str:
    return moment.astimezone(UTC).isoformat(timespec="seconds")


def _choice(name: str, value: str, allowed: Iterable[str]) -> str:
    allowed = tuple(allowed)
    if value not in allowed:
        raise UsageError(f"{name} {value[:40]!r}: not a {NAMES[name]}; give one of {', '.join(allowed)}")
    return value


def parse(items: Iterable[tuple[str, str]]) -> tuple[PageFilters, int]:
    """The filters and the page number (from 1) of a query string's ``items``; empty fields select everything."""
    given: dict[str, str] = {}
    for name, value in items:
        if name not in NAMES:
            raise UsageError(f"{name[:40]!r}: not a filter; the filters are {', '.join(NAMES)}")
        if value.strip():
            given[name] = value.strip()
    since = before = None
    if "from" in given:
        since = _utc(_moment("from", given["from"])[0])
    if "until" in given:
        moment, whole_day = _moment("until", given["until"])
        before = _utc(moment + (timedelta(days=1) if whole_day else timedelta(seconds=1)))
    if since is not None and before is not None and before <= since:
        raise UsageError(f"until {given['until']!r} is before from {given['from']!r}; give a last day on or after "
                         "the first")
    page = given.get("page", "1")
    if not page.isdigit() or not 1 <= int(page) <= 1_000_000:
        raise UsageError(f"page {page[:40]!r}: not a page number; give 1, 2, ...")
    filters = PageFilters(
        serial=_serial(given["serial"]) if "serial" in given else None,
        station=_text("station", given["station"]) if "station" in given else None,
        profile=_text("profile", given["profile"]) if "profile" in given else None,
        kind=_choice("kind", given["kind"], KINDS) if "kind" in given else None,
        verdict=_choice("verdict", given["verdict"], VERDICTS) if "verdict" in given else None,
        since_utc=since, before_utc=before, given_from=given.get("from"), given_until=given.get("until"))
    return filters, int(page)
