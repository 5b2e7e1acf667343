"""What allure says of a test is what the run says of it: the test's result in the run summary
(plugin/run_record.py) sets its area (epic and parent suite), suite module (feature), clause or manual section
(story), basis (tag ``basis: cia``) and outcome (status and message).

allure-pytest judges a report before this plugin does (hooks.py's report wrapper is the outermost): a test whose
only problem broke a rule we inferred, a device that stopped answering or a test held out by a kept error would
read as failed or broken there. The status is set again here, on the result allure still holds open. Called only
where allure-pytest writes results: allure is imported here, never in a run without ``--allure``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from encoder_conformance.run_summary import TestResult

#: our outcome -> allure's status (a warning passed; its category says why: plugin/allure_run.py)
STATUS: dict[str, str] = {"passed": "passed", "warning": "passed", "failed": "failed", "error": "broken",
                          "skipped": "skipped"}
WARNING_PREFIX = "warning: "
BASIS_TAG = "basis: "
_OURS = frozenset({"parentSuite", "epic", "feature", "story"})


def feature_of(nodeid: str) -> str:
    """The suite module in words: ``suites/test_nmt_state_machine.py::...`` -> ``nmt state machine``."""
    return Path(nodeid.split("::", 1)[0]).stem.removeprefix("test_").replace("_", " ")


def labels_of(result: TestResult) -> list[tuple[str, str]]:
    """(allure label, value) for the test's area, module, clause and basis."""
    labels = [("parentSuite", result.area), ("epic", result.area), ("feature", feature_of(result.nodeid))]
    if result.source:
        labels.append(("story", result.source))
    if result.basis:
        labels.append(("tag", BASIS_TAG + result.basis))
    return labels


def message_of(result: TestResult) -> str | None:
    """The status message: the run summary's (skip reason, failure), a warning's problems after ``warning: ``."""
    if result.outcome == "warning":
        return WARNING_PREFIX + (result.message or "a rule we inferred was broken")
    return result.message or None


def _ours(name: str, value: str) -> bool:
    return name in _OURS or (name == "tag" and value.startswith(BASIS_TAG))


def amend(item: pytest.Item, result: TestResult | None) -> None:
    """Set the open allure result of ``item`` from its run-summary ``result`` (again after each phase)."""
    listener = item.config.pluginmanager.get_plugin("allure_listener")
    logger = getattr(listener, "allure_logger", None)  # allure-pytest's: the results it has not written yet
    test = logger.get_test(None) if logger is not None and result is not None else None
    if test is None or result is None:
        return
    from allure_commons.model2 import Label, StatusDetails

    test.labels = [label for label in test.labels if not _ours(label.name, label.value)]
    test.labels.extend(Label(name=name, value=value) for name, value in labels_of(result))
    test.status = STATUS[result.outcome]
    details = test.statusDetails
    trace = details.trace if details is not None and result.outcome in ("failed", "error") else None
    message = message_of(result)
    test.statusDetails = StatusDetails(message=message, trace=trace) if message or trace else None
