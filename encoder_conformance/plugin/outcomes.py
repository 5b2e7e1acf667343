"""What an exception in a test says: a finding about the device, or an internal error of the tool (the one rule).

A **finding about the device** (the test fails; it counts in its area and its basis):

- ``AssertionError``: a check's verdict. The dut layer raises these for what the device did wrong: an SDO
  request left unanswered or answered with the wrong frame (``DeviceLink._timeout``, ``expect_abort``,
  ``dut.nmt.reset_node``), a boot-up that did not come;
- ``pytest.fail()`` (pytest's ``Failed``): a fixture's or test's explicit verdict;
- ``DutLostError``: the device stopped answering (not ``BusLostError``: below);
- canopen's ``SdoError`` family: ``SdoAbortedError`` (the device refused a request the test expected it to
  serve; the dut layer raises it as ``SdoAborted``) and ``SdoCommunicationError`` (canopen's client got no or a
  wrong answer);
- an exception group (hypothesis's several failures, its ``FlakyFailure``) whose every member is one of these.

**Not run** (skipped, never a verdict): ``BusLostError``, the tester lost its bus; ``NotJudged``, a check in scope
could not judge the device (e.g. ``HeldByPersistentError``: it keeps an error that holds it out of the state the
test needs; not testable, see coverage.py and plugin/skips.py).

Everything else is an **internal error of the tool**: ``AttributeError``, ``TypeError``, ``KeyError``,
``NameError``, ``ValueError``, an error raised inside a library, hypothesis's health checks and usage errors.
Its outcome is "error", shown as "internal error of the tool: please report it"; it is never counted against
the device, an area or a basis, and the run exits 3 (``RunExit.INTERNAL_ERROR``) when nothing else failed.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from canopen.sdo.exceptions import SdoError

from encoder_conformance.errors import BusLostError, DutLostError, NotJudged

#: the exception types that are findings about the device (see the module's docstring)
DEVICE_FINDINGS: tuple[type[BaseException], ...] = (AssertionError, pytest.fail.Exception, DutLostError,
                                                         SdoError)
INTERNAL_ERROR_TEXT = "internal error of the tool: please report it"
#: user property (name, value) on a report whose exception is an internal error
INTERNAL = ("verdict", "internal error")


def is_device_finding(exc: BaseException) -> bool:
    """True where ``exc`` is a finding about the device (a group: every member is one)."""
    if isinstance(exc, BusLostError | NotJudged):
        return False
    if isinstance(exc, BaseExceptionGroup):
        return all(is_device_finding(member) for member in exc.exceptions)
    return isinstance(exc, DEVICE_FINDINGS)


def is_internal_error(report: pytest.TestReport) -> bool:
    """The report's failure is an internal error of the tool (marked by ``classify``)."""
    return INTERNAL in report.user_properties


def classify(item: pytest.Item, call: pytest.CallInfo[None], report: pytest.TestReport) -> None:
    """Mark a failure whose exception is no finding about the device as an internal error (any phase)."""
    if not report.failed or call.excinfo is None or is_device_finding(call.excinfo.value):
        return
    report.user_properties.append(INTERNAL)
    item.user_properties.append(INTERNAL)  # JUnit writes the item's properties
    exc = call.excinfo.value
    report.longrepr = (f"{INTERNAL_ERROR_TEXT} ({report.when}: {type(exc).__name__}: {exc})\n"
                       f"not a finding about the device: not counted in any verdict\n\n{report.longrepr}")


def junit_internal_errors_as_errors(junit: Path) -> int:
    """In JUnit, an internal error is an ``<error>`` (the tool broke), not a ``<failure>`` of the device: CI
    systems show the two apart. Rewrites pytest's file after it was written; returns how many were changed."""
    if not junit.is_file():
        return 0
    tree = ET.parse(junit)
    changed = 0
    for suite in tree.getroot().iter("testsuite"):
        for case in suite.iter("testcase"):
            marked = any((p.get("name"), p.get("value")) == INTERNAL for p in case.iter("property"))
            for child in case if marked else ():
                if child.tag == "failure":
                    child.tag = "error"
                    changed += 1
        if changed:
            suite.set("failures", str(sum(1 for c in suite.iter("testcase") if c.find("failure") is not None)))
            suite.set("errors", str(sum(len(c.findall("error")) for c in suite.iter("testcase"))))
    if changed:
        tree.write(junit, encoding="utf-8", xml_declaration=True)
    return changed
