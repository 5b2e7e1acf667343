"""The page's filters, read from the query string by a pydantic model (``PageQuery``): a filter it cannot use is a
UsageError whose message says which and what to give, one sentence per bad filter (the page answers it with 400
and that message, never a traceback)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, fields
from datetime import UTC, datetime, timedelta
from urllib.parse import urlencode

from pydantic import BaseModel, ConfigDict, Field, ValidationError, ValidationInfo, field_validator, model_validator
from pydantic_core import ErrorDetails, PydanticCustomError

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


class PageQuery(BaseModel):
    """The query string as the page's form sends it (empty fields left out): each filter checked by its validator,
    an unknown name refused (``extra="forbid"``)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    serial: str | None = None
    station: str | None = None
    profile: str | None = None
    kind: str | None = None
    verdict: str | None = None
    given_from: str | None = Field(default=None, alias="from")
    given_until: str | None = Field(default=None, alias="until")
    page: int = 1

    @field_validator("serial")
    @classmethod
    def _serial(cls, value: str) -> str:
        if value.lower().startswith("0x"):
            try:
                return str(int(value, 16))
            except ValueError:
                raise _bad(f"serial {value!r}: not a number; give it in decimal or as 0x-hex") from None
        return _text("serial", value)

    @field_validator("station", "profile")
    @classmethod
    def _printable(cls, value: str, info: ValidationInfo) -> str:
        return _text(str(info.field_name), value)

    @field_validator("kind")
    @classmethod
    def _kind(cls, value: str) -> str:
        return _choice("kind", value, KINDS)

    @field_validator("verdict")
    @classmethod
    def _verdict(cls, value: str) -> str:
        return _choice("verdict", value, VERDICTS)

    @field_validator("given_from", "given_until")
    @classmethod
    def _date(cls, value: str, info: ValidationInfo) -> str:
        _moment("from" if info.field_name == "given_from" else "until", value)
        return value

    @field_validator("page", mode="before")
    @classmethod
    def _page(cls, value: object) -> object:
        if isinstance(value, str) and not (value.isdigit() and 1 <= int(value) <= 1_000_000):
            raise _bad(f"page {value[:40]!r}: not a page number; give 1, 2, ...")
        return value

    @model_validator(mode="after")
    def _days_in_order(self) -> PageQuery:
        since, before = self.since_utc, self.before_utc
        if since is not None and before is not None and before <= since:
            raise _bad(f"until {self.given_until!r} is before from {self.given_from!r}; give a last day on or after "
                       "the first")
        return self

    @property
    def since_utc(self) -> str | None:
        """started_utc >= this: the first day's local midnight (or the date-time given), in UTC."""
        return None if self.given_from is None else _utc(_moment("from", self.given_from)[0])

    @property
    def before_utc(self) -> str | None:
        """started_utc < this: the day after the last day (or a second after the date-time given), in UTC."""
        if self.given_until is None:
            return None
        moment, whole_day = _moment("until", self.given_until)
        return _utc(moment + (timedelta(days=1) if whole_day else timedelta(seconds=1)))

    def filters(self) -> PageFilters:
        return PageFilters(serial=self.serial, station=self.station, profile=self.profile, kind=self.kind,
                           verdict=self.verdict, since_utc=self.since_utc, before_utc=self.before_utc,
                           given_from=self.given_from, given_until=self.given_until)


def _bad(message: str) -> PydanticCustomError:
    """A filter's error as pydantic reports it, its message as the page shows it."""
    return PydanticCustomError("bad_filter", "{message}", {"message": message})


def _text(name: str, value: str) -> str:
    if len(value) > MAX_TEXT or any(ord(c) < 32 for c in value):
        raise _bad(f"{name} {value[:40]!r}: not a {NAMES[name]}; give at most {MAX_TEXT} printable characters")
    return value


def _moment(name: str, value: str) -> tuple[datetime, bool]:
    """A date (local midnight) or an ISO date-time (local time unless it has an offset); True for a date."""
    try:
        moment = datetime.fromisoformat(value)
    except ValueError:
        raise _bad(f"{name} {value[:40]!r}: not a date; give YYYY-MM-DD (or an ISO date-time such as "
                   "2026-11-26T08:00)") from None
    return (moment if moment.tzinfo else moment.astimezone()), len(value) <= 10


def _utc(moment: datetime) -> str:
    return moment.astimezone(UTC).isoformat(timespec="seconds")


def _choice(name: str, value: str, allowed: tuple[str, ...]) -> str:
    if value not in allowed:
        raise _bad(f"{name} {value[:40]!r}: not a {NAMES[name]}; give one of {', '.join(allowed)}")
    return value


def _message(error: ErrorDetails) -> str:
    if error["type"] == "extra_forbidden":
        return f"{str(error['loc'][0])[:40]!r}: not a filter; the filters are {', '.join(NAMES)}"
    if error["type"] == "bad_filter":
        return error["msg"]
    return f"{'.'.join(map(str, error['loc']))}: {error['msg']}"  # not from a query string's text


def parse(items: Iterable[tuple[str, str]]) -> tuple[PageFilters, int]:
    """The filters and the page number (from 1) of a query string's ``items``; empty fields select everything, a
    name given twice counts as given last."""
    given = {name: value.strip() for name, value in items if value.strip() or name not in NAMES}
    try:
        query = PageQuery.model_validate(given)
    except ValidationError as exc:
        raise UsageError("; ".join(_message(error) for error in exc.errors())) from None
    return query.filters(), query.page
