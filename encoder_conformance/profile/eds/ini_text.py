"""Reading a vendor EDS as text: encoding, section and key spelling, comments, numbers, DummyUsage."""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field

from encoder_conformance.profile.eds.numbers import (
    _KEY_ALIASES,
    _KEY_PATTERNS,
    _OBJECT_SECTION,
    _SECTION_ALIASES,
    _SECTION_HEADER,
    Sections,
    parse_number,
)

logger = logging.getLogger(__name__)


# --------------------------------------------------------------------------- cleaning


@dataclass
class CleanedEds:
    """The cleaned EDS text plus what was changed to get there."""

    text: str
    sections: Sections
    origins: dict[str, str]  # cleaned section -> section of the vendor file it came from
    fixes: list[str] = field(default_factory=list)
    #: section -> the ``;StorageLocation=`` comment of EDS generators (CANopenEditor: RAM, PERSIST_COMM, ...)
    storage_locations: dict[str, str] = field(default_factory=dict)
    #: section -> the line of the vendor file its header is on (for warnings that name the line)
    lines: dict[str, int] = field(default_factory=dict)
    #: (section, key) -> the line of the vendor file the key is on
    key_lines: dict[tuple[str, str], int] = field(default_factory=dict)


def _decode(data: bytes, fixes: list[str]) -> str:
    """Text of the file: UTF-8 (BOM removed), UTF-16 with BOM, else Windows-1252/Latin-1."""
    if data.startswith(b"\xef\xbb\xbf"):
        fixes.append("removed the UTF-8 byte-order mark")
        return data[3:].decode("utf-8", errors="replace")
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        fixes.append("decoded UTF-16 (byte-order mark)")
        return data.decode("utf-16")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        pass
    try:
        text = data.decode("cp1252")
        fixes.append("file is not UTF-8; decoded as Windows-1252")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
        fixes.append("file is not UTF-8; decoded as Latin-1")
    return text


def _canonical_section(name: str) -> str:
    match = _OBJECT_SECTION.match(name)
    if match is None:
        return _SECTION_ALIASES.get(name.lower(), name)
    index = match.group(1).upper()
    if match.group(2):
        return f"{index}sub{int(match.group(3), 16):X}"
    if match.group(4):
        return index + match.group(4).capitalize()
    return index


def _canonical_key(key: str) -> str:
    if key.lower() in _KEY_ALIASES:
        return _KEY_ALIASES[key.lower()]
    for pattern, template in _KEY_PATTERNS:
        match = pattern.match(key)
        if match:
            return template.format(match.group(1))
    return key


def _strip_inline_comment(value: str) -> tuple[str, bool]:
    """Remove a ' ; comment' tail (as canopen's parser would) and trailing blanks."""
    stripped = re.sub(r"\s+;.*$", "", value).strip()
    return stripped, stripped != value.strip()


class _IniReader:
    """Lenient INI tokenizer: merges duplicates and normalises names, recording every change."""

    def __init__(self, fixes: list[str]) -> None:
        self.fixes = fixes
        self.sections: Sections = {}
        self.origins: dict[str, str] = {}
        self.renamed_keys: dict[str, list[str]] = {}
        self.inline_comments = 0
        self.current: str | None = None
        self.storage_locations: dict[str, str] = {}
        self.lines: dict[str, int] = {}
        self.key_lines: dict[tuple[str, str], int] = {}

    def read(self, text: str) -> Sections:
        for number, raw in enumerate(text.splitlines(), start=1):
            line = raw.strip()
            if not line or line.startswith((";", "#", "//")):
                self._comment(line)
                continue
            header = _SECTION_HEADER.match(line)
            if header:
                self._section(header.group(1).strip())
                assert self.current is not None
                self.lines.setdefault(self.current, number)
            elif "=" in line and self.current is not None and line.partition("=")[0].strip():
                key, _, value = line.partition("=")
                self.key_lines[self.current, _canonical_key(key.strip())] = number
                self._option(key.strip(), value)
            else:
                self.fixes.append(f"line {number}: ignored {line[:40]!r} (not a section or key=value)")
        self._summarise()
        return self.sections

    def _comment(self, line: str) -> None:
        """Keep ``;StorageLocation=X`` (a comment to INI readers, the storage group to EDS generators)."""
        key, _, value = line.lstrip(";#/ ").partition("=")
        if self.current is not None and key.strip().lower() == "storagelocation" and value.strip():
            self.storage_locations[self.current] = value.strip()

    def _section(self, name: str) -> None:
        canonical = _canonical_section(name)
        if canonical != name:
            self.fixes.append(f"section [{name}] renamed to [{canonical}]")
        if canonical in self.sections:
            self.fixes.append(f"section [{canonical}] appears more than once; merged (later keys win)")
        self.sections.setdefault(canonical, {})
        self.origins.setdefault(canonical, canonical)
        self.current = canonical

    def _option(self, key: str, raw_value: str) -> None:
        assert self.current is not None
        section = self.sections[self.current]
        value, had_comment = _strip_inline_comment(raw_value)
        self.inline_comments += had_comment
        canonical = _canonical_key(key)
        if canonical != key:
            self.renamed_keys.setdefault(self.current, []).append(f"{key} -> {canonical}")
        if canonical in section and section[canonical] != value:
            self.fixes.append(
                f"[{self.current}] {canonical} given twice ({section[canonical]!r}, {value!r}); kept the last"
            )
        section[canonical] = value

    def _summarise(self) -> None:
        for section, renames in self.renamed_keys.items():
            self.fixes.append(f"[{section}] key casing: {', '.join(renames)}")
        if self.inline_comments:
            self.fixes.append(f"removed {self.inline_comments} inline ';' comment(s)")


def _fix_numbers(sections: Sections, name: str, keys: tuple[str, ...], fixes: list[str]) -> None:
    """Rewrite ``keys`` (and BaudRate_x/DummyNNNN) of a section as numbers canopen reads with int(x, 0)."""
    section = sections.get(name, {})
    for key in [k for k in section if k in keys or re.fullmatch(r"BaudRate_\d+|Dummy\d{4}", k)]:
        old = section[key]
        value = parse_number(old)
        if value is None:
            fixes.append(f"[{name}] {key}={old!r} is not a number; removed")
            del section[key]
        elif not re.fullmatch(r"[+-]?0x[0-9a-f]+", old, re.I) and str(value) != old:
            _note_number_rewrite(name, key, old, value, fixes)
            section[key] = str(value)


def _note_number_rewrite(name: str, key: str, old: str, value: int, fixes: list[str]) -> None:
    if re.fullmatch(r"0\d+", old.strip()) and value >= 8:
        fixes.append(f"[{name}] {key}={old!r} read as decimal {value} (C-style octal would differ; check)")
    else:
        fixes.append(f"[{name}] {key}={old!r} rewritten as {value}")


def _fix_dummy_usage(sections: Sections, fixes: list[str]) -> None:
    """canopen reads Dummy0001..Dummy0007 without a fallback once [DummyUsage] exists."""
    usage = sections.get("DummyUsage")
    if usage is None:
        return
    _fix_numbers(sections, "DummyUsage", (), fixes)
    missing = [f"Dummy{i:04d}" for i in range(1, 8) if f"Dummy{i:04d}" not in usage]
    for key in missing:
        usage[key] = "0"
    if missing:
        fixes.append(f"[DummyUsage] added missing {', '.join(missing)} = 0")


def _fix_comments(sections: Sections, fixes: list[str]) -> None:
    comments = sections.get("Comments")
    if comments is None:
        return
    numbers = [int(k[4:]) for k in comments if re.fullmatch(r"Line\d+", k)]
    declared = parse_number(comments.get("Lines", ""))
    count = max([*numbers, declared or 0])
    missing = [n for n in range(1, count + 1) if f"Line{n}" not in comments]
    for n in missing:
        comments[f"Line{n}"] = ""
    if missing:
        fixes.append(f"[Comments] added empty {', '.join(f'Line{n}' for n in missing)} (Lines={count})")
    if declared != count:
        fixes.append(f"[Comments] Lines={comments.get('Lines')!r} but Line1..Line{count} given; fixed")
    comments["Lines"] = str(count)


