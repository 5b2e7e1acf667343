"""The run's coverage in JUnit: a property with the overall verdict and one testcase, "coverage of the run", that
fails where the run is INCOMPLETE, so a CI system that reads only JUnit does not show a run as green that left checks
in its scope untested (pytest writes the file; this adds to it afterwards)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from encoder_conformance.coverage import Kind
from encoder_conformance.run_summary import RunSummary

CASE_NAME = "coverage of the run"
CLASS_NAME = "encoder_conformance.coverage"
PROPERTY = "coverage verdict"


def _failure_text(summary: RunSummary) -> str:
    held = summary.with_kind(Kind.NOT_TESTABLE)
    lines = [f"INCOMPLETE: {len(held)} check(s) in scope were not testable (areas: "
             f"{', '.join(summary.incomplete_areas())})"]
    lines += [f"{r.nodeid}: {r.message.splitlines()[0] if r.message else ''}" for r in held[:20]]
    return "\n".join(lines)


def add(junit: Path, summary: RunSummary) -> bool:
    """Add the verdict property and the coverage testcase to the first testsuite; False where there is no file."""
    if not junit.is_file():
        return False
    tree = ET.parse(junit)
    root = tree.getroot()
    suite = root if root.tag == "testsuite" else root.find("testsuite")
    if suite is None:
        return False
    properties = suite.find("properties")
    if properties is None:
        properties = ET.Element("properties")
        suite.insert(0, properties)
    ET.SubElement(properties, "property", name=PROPERTY, value=summary.overall)
    case = ET.SubElement(suite, "testcase", classname=CLASS_NAME, name=CASE_NAME, time="0")
    if summary.overall == "INCOMPLETE":
        failure = ET.SubElement(case, "failure", message="INCOMPLETE: checks in scope were not testable")
        failure.text = _failure_text(summary)
        suite.set("failures", str(int(suite.get("failures", "0")) + 1))
    suite.set("tests", str(int(suite.get("tests", "0")) + 1))
    tree.write(junit, encoding="utf-8", xml_declaration=True)
    return True
