"""The outcome of one run for people and machines: the device, the settings, one result per test, a
verdict per area and overall. Written by every run as ``run-summary.json`` in its report folder; read by
the report's first screen, the acceptance certificate and the history database.

Pure data (no pytest): the plugin fills it (plugin/run_record.py), everything else reads it.

Outcomes: "failed" is a finding about the device; "error" is an internal error of the tool (an exception that
is no finding about the device: plugin/outcomes.py), counted in no area and no verdict but the overall
INTERNAL ERROR of a run where nothing failed. A "skipped" result keeps its kind (coverage.Kind): out of scope (not
applicable, not available, not selected) it is only listed; in scope it is not testable (the area is INCOMPLETE) or
inconclusive (the area is at most PASS WITH WARNINGS). PASS means every check in scope ran and passed.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

from encoder_conformance.coverage import Kind, kind_of

SUMMARY_FILE = "run-summary.json"

#: the areas of a report, in the order a reader expects them
AREAS: tuple[str, ...] = ("identity", "working order", "object dictionary", "SDO", "NMT", "error control", "EMCY",
                          "PDO", "store/restore", "LSS", "encoder function", "CAM", "other")

#: suite module -> area (a module not named here is "other")
MODULE_AREAS: dict[str, str] = {
    "test_identity": "identity",
    "test_working_order": "working order",  # goods-in only: an error at start-up, NMT start
    "test_object_dictionary": "object dictionary",
    "test_value_domain": "object dictionary",
    "test_sdo_protocol": "SDO",
    "test_sdo_block": "SDO",
    "test_sdo_fuzz": "SDO",
    "test_nmt": "NMT",
    "test_nmt_state_machine": "NMT",
    "test_heartbeat": "error control",
    "test_error_control": "error control",
    "test_emcy": "EMCY",
    "test_emcy_history": "EMCY",
    "test_sync_objects": "PDO",  # the SYNC consumer objects: what synchronous TPDOs run on
    "test_pdo": "PDO",
    "test_pdo_comm": "PDO",
    "test_pdo_mapping": "PDO",
    "test_pdo_repeat": "PDO",
    "test_pdo_timing": "PDO",
    "test_store_restore": "store/restore",
    "test_manufacturer_store": "store/restore",
    "test_lss": "LSS",
    "test_encoder_position": "encoder function",
    "test_encoder_properties": "encoder function",
    "test_work_area": "encoder function",
    "test_cam": "CAM",
}

#: where a serial number comes from, in order of trust
SERIAL_KEYS = ("serial number (1018h.4)", "serial number (650Bh)", "serial number (label)")

Outcome = Literal["passed", "failed", "warning", "skipped", "error"]
Verdict = Literal["PASS", "FAIL", "PASS WITH WARNINGS", "INCOMPLETE", "COULD NOT TEST", "INTERNAL ERROR", "NOT RUN"]
INTERNAL_ERROR_TEXT = "internal error of the tool: please report it"


def area_of(nodeid: str) -> str:
    """The area of a test from its pytest node id (``suites/test_nmt.py::test_x[...]``)."""
    module = Path(nodeid.split("::", 1)[0]).stem
    return MODULE_AREAS.get(module, "other")


@dataclass
class TestResult:
    """One test's verdict and what it rests on."""

    __test__ = False  # not a pytest test class

    nodeid: str
    area: str
    outcome: Outcome
    basis: str | None = None  # cia / manual / inferred
    source: str | None = None  # the clause or manual section
    message: str = ""  # the failure (expected vs observed), the skip reason, the warning
    duration_s: float = 0.0
    trace: str | None = None  # the frame trace, relative to the report folder
    skip_kind: str | None = None  # a skip's coverage.Kind value ("not applicable", "not testable", ...)
    hold: str | None = None  # in scope: the coverage.Hold that kept the check from judging

    @property
    def kind(self) -> Kind | None:
        """Why a skipped check did not judge. A summary written before skips were typed kept no kind: read from the
        message's first words, any other skip out of scope, as that version counted it (its record keeps its
        verdict)."""
        if self.outcome != "skipped":
            return None
        return Kind(self.skip_kind) if self.skip_kind else kind_of(self.message, Kind.NOT_APPLICABLE)


@dataclass
class AreaVerdict:
    """The counts of one area and its verdict."""

    area: str
    passed: int = 0
    failed: int = 0
    warnings: int = 0
    skipped: int = 0  # every skip; of them:
    not_testable: int = 0  # in scope, the device's state kept the check from judging
    inconclusive: int = 0  # in scope, the tester's host was late
    out_of_scope: int = 0  # not applicable, not available, not selected: listed, never counted

    @property
    def verdict(self) -> Verdict:
        """FAIL outranks INCOMPLETE (a check in scope not testable), which outranks PASS WITH WARNINGS (a warning or
        an inconclusive check); PASS only where every check in scope ran and passed."""
        if self.failed:
            return "FAIL"
        if self.not_testable:
            return "INCOMPLETE"
        if self.warnings or self.inconclusive:
            return "PASS WITH WARNINGS"
        return "PASS" if self.passed else "NOT RUN"

    def count(self, result: TestResult) -> None:
        """Count a test's outcome; an internal error of the tool ("error") is no verdict about the device."""
        name = {"passed": "passed", "failed": "failed", "warning": "warnings", "skipped": "skipped"}.get(result.outcome)
        if name is not None:
            setattr(self, name, getattr(self, name) + 1)
        kind = result.kind
        if kind is not None:
            which = {Kind.NOT_TESTABLE: "not_testable", Kind.INCONCLUSIVE: "inconclusive"}.get(kind, "out_of_scope")
            setattr(self, which, getattr(self, which) + 1)


@dataclass
class RunSummary:
    """Everything a certificate, a history entry or the report's first screen needs."""

    kind: str  # "run" or "accept"
    started: str  # ISO 8601, local time with offset
    profile_id: str
    profile_sha256: str
    duration_s: float = 0.0
    identity: dict[str, str] = field(default_factory=dict)  # as read from the device (1000h, 1008h, 1018h)
    settings: dict[str, str] = field(default_factory=dict)  # each with its source: "250000 (from station file)"
    station: str | None = None
    operator: str | None = None
    results: list[TestResult] = field(default_factory=list)
    exit_code: int | None = None
    could_not_test: str | None = None  # why the run stopped before it could judge the device
    device_failed: str | None = None  # the finding that stopped the run (start-up check, a device gone silent)
    not_run: int = 0  # tests collected but not run (the run stopped early)
    device_restored: bool | None = None
    device_memory: str | None = None  # the memory is not as found where the values are (dut/store/boot_memory.py)
    report_dir: str | None = None
    time_budget: dict[str, Any] | None = None  # where the run's time went (plugin/time_budget.py)
    scope: dict[str, str] = field(default_factory=dict)  # what the station and the options left out, declared up front
    deselected: int = 0  # tests the selection (-k, -m) left out: scope, not counted
    late_frames: list[str] = field(default_factory=list)  # frames after the window that proved them absent

    @property
    def serial(self) -> str | None:
        """The serial number in decimal, as the label on the device shows it: 1018h sub 4, else 650Bh, else the
        label's (--label-serial) for a device that reports none."""
        for key in SERIAL_KEYS:
            text = self.identity.get(key)
            if text is not None and not text.startswith("-"):
                return text.split()[0]
        return None

    @property
    def revision(self) -> str | None:
        text = self.identity.get("revision (1018h.3)")
        return None if text in (None, "-") else text

    def areas(self) -> list[AreaVerdict]:
        """The verdict per area, in AREAS order; areas with no test left out."""
        by_area = {area: AreaVerdict(area) for area in AREAS}
        for result in self.results:
            by_area.setdefault(result.area, AreaVerdict(result.area)).count(result)
        return [v for v in by_area.values() if v.passed or v.failed or v.warnings or v.skipped]

    @property
    def overall(self) -> Verdict:
        if self.could_not_test:
            return "COULD NOT TEST"
        verdicts = {area.verdict for area in self.areas()}
        if "FAIL" in verdicts or self.device_restored is False or self.device_failed:
            return "FAIL"
        if self.internal_errors:
            return "INTERNAL ERROR"  # the run did not judge what those tests check: no PASS
        if "INCOMPLETE" in verdicts:
            return "INCOMPLETE"  # a check in scope did not judge the device: no PASS either
        if not verdicts - {"NOT RUN"}:
            return "NOT RUN"
        return "PASS WITH WARNINGS" if "PASS WITH WARNINGS" in verdicts else "PASS"

    @property
    def internal_errors(self) -> list[TestResult]:
        """Tests that ended in an internal error of the tool (outside every area verdict)."""
        return self.with_outcome("error")

    def failing_areas(self) -> list[str]:
        return [area.area for area in self.areas() if area.verdict == "FAIL"]

    def incomplete_areas(self) -> list[str]:
        return [area.area for area in self.areas() if area.verdict == "INCOMPLETE"]

    def with_kind(self, *kinds: Kind) -> list[TestResult]:
        """The skipped results of those kinds (e.g. every check not testable)."""
        return [r for r in self.results if r.kind in kinds]

    def with_outcome(self, *outcomes: Outcome) -> list[TestResult]:
        return [r for r in self.results if r.outcome in outcomes]

    def coverage(self) -> dict[str, Any]:
        """What the run checked, what it could not and why (counts per kind, and per hold in scope)."""
        kinds: dict[str, int] = {}
        holds: dict[str, int] = {}
        for result in self.with_outcome("skipped"):
            kind = result.kind
            if kind is not None:
                kinds[kind.value] = kinds.get(kind.value, 0) + 1
            if result.hold:
                holds[result.hold] = holds.get(result.hold, 0) + 1
        checked = len(self.with_outcome("passed", "failed", "warning"))
        return {"checked": checked, "skipped_by_kind": kinds, "holds": holds, "deselected": self.deselected,
                "scope": self.scope}

    def to_json(self) -> str:
        data = asdict(self)
        data["overall"] = self.overall
        data["serial"] = self.serial
        data["areas"] = [{**asdict(a), "verdict": a.verdict} for a in self.areas()]
        data["coverage"] = self.coverage()
        return json.dumps(data, indent=1)

    @classmethod
    def from_json(cls, text: str) -> RunSummary:
        data = json.loads(text)
        for derived in ("overall", "serial", "areas"):
            data.pop(derived, None)
        data["results"] = [TestResult(**r) for r in data.get("results", [])]
        data.pop("coverage", None)
        return cls(**data)

    def write(self, folder: Path) -> Path:
        path = folder / SUMMARY_FILE
        path.write_text(self.to_json(), encoding="utf-8")
        return path

    @classmethod
    def read(cls, folder_or_file: Path) -> RunSummary:
        path = folder_or_file / SUMMARY_FILE if folder_or_file.is_dir() else folder_or_file
        return cls.from_json(path.read_text(encoding="utf-8"))

