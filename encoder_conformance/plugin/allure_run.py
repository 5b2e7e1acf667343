"""The run as allure shows it beside its tests, from the run summary, written into the allure results folder at
the session's end: ``environment.properties`` (the run's verdict, the verdict per area, the device's identity,
the profile and every setting with its source), ``categories.json`` (device failure, internal error, warning,
and the skips by kind, told apart by the reason's first words) and ``executor.json`` (the report's name: profile
and verdict). Plain files: nothing of allure is imported.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from encoder_conformance.plugin.allure_labels import WARNING_PREFIX
from encoder_conformance.run_summary import RunSummary


def _starts_with(*words: str) -> str:
    """A Java regex (allure matches the whole message) for a reason that starts with one of ``words``."""
    return r"(?is)(skipped: )?(" + "|".join(words) + r")\b.*"


#: allure's categories, one per kind of outcome that is not a plain pass; skips by their reason's first words
#: (``not applicable: ...``), so a reason typed or worded anew keeps its category while it keeps its prefix
CATEGORIES: list[dict[str, Any]] = [
    {"name": "device failure", "matchedStatuses": ["failed"]},
    {"name": "internal error of the tool", "matchedStatuses": ["broken"]},
    {"name": "warning: a rule we inferred was broken", "matchedStatuses": ["passed"],
     "messageRegex": "(?s)" + WARNING_PREFIX + ".*"},
    {"name": "not testable", "matchedStatuses": ["skipped"], "messageRegex": _starts_with("not testable")},
    {"name": "inconclusive", "matchedStatuses": ["skipped"], "messageRegex": _starts_with("inconclusive")},
    {"name": "not applicable", "matchedStatuses": ["skipped"], "messageRegex": _starts_with("not applicable")},
    {"name": "could not test", "matchedStatuses": ["skipped"],
     "messageRegex": _starts_with("could not test", "not run to the end")},
    {"name": "bench equipment not available", "matchedStatuses": ["skipped"],
     "messageRegex": _starts_with("not available")},
    {"name": "not selected (e.g. destructive: not run without --allow-destructive)", "matchedStatuses": ["skipped"],
     "messageRegex": _starts_with("not selected", "destructive")},
]


def environment(summary: RunSummary) -> dict[str, str]:
    """What allure's environment table shows: the verdict first, then the areas, the device and the settings."""
    values: dict[str, str] = {"verdict": summary.overall}
    if summary.could_not_test:
        values["could not test"] = summary.could_not_test
    if summary.device_failed:
        values["the run stopped"] = summary.device_failed
    values.update({f"area {area.area}": area.verdict for area in summary.areas()})
    if summary.device_restored is not None:
        values["device given back as found"] = "yes" if summary.device_restored else "NO"
    values.update({"profile": summary.profile_id, "profile sha256": summary.profile_sha256, "run kind": summary.kind})
    values.update({key: value for key, value in (("station", summary.station), ("operator", summary.operator))
                   if value})
    values.update({f"identity {key}": value for key, value in summary.identity.items()})
    values.update(summary.settings)
    return values


def _escape(text: str, key: bool) -> str:
    """Java properties escaping, ASCII only (allure reads the file as ISO 8859-1)."""
    out = []
    for index, char in enumerate(text):
        if char in "\\=:#!" or (char == " " and (key or index == 0)):
            out.append("\\" + char)
        elif char in "\n\r\t":
            out.append({"\n": "\\n", "\r": "\\r", "\t": "\\t"}[char])
        elif " " <= char <= "~":
            out.append(char)
        else:  # \uXXXX, a character beyond the first plane as its UTF-16 pair
            units = char.encode("utf-16-be")
            out.extend(f"\\u{units[i]:02x}{units[i + 1]:02x}" for i in range(0, len(units), 2))
    return "".join(out)


def properties_text(values: dict[str, str]) -> str:
    """``key=value`` lines as java.util.Properties reads them."""
    return "".join(f"{_escape(key, True)}={_escape(value, False)}\n" for key, value in values.items())


def write(folder: Path, summary: RunSummary) -> None:
    """Write environment.properties, categories.json and executor.json into the allure results ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "environment.properties").write_text(properties_text(environment(summary)), encoding="ascii")
    (folder / "categories.json").write_text(json.dumps(CATEGORIES, indent=1), encoding="utf-8")
    executor = {"name": "encoder-conformance", "type": "encoder-conformance",
                "reportName": f"{summary.profile_id}: {summary.overall}"}
    (folder / "executor.json").write_text(json.dumps(executor, indent=1), encoding="utf-8")
