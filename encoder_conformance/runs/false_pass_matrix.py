"""The false-PASS matrix: every way a check can end without judging the device, taken by a twin fault, must end the run
FAIL or INCOMPLETE, never PASS.

Beside the fault matrix (a fault must make a test fail) this one proves the other direction: a defective device that
keeps a check from judging (it keeps an error, never reaches a state, sends nothing to compare) must not pass. For each
:class:`~encoder_conformance.coverage.Hold` a device can cause, one :class:`FalsePassPath` names a twin fault (or
conformant variant) that makes a check take that hold, the profile and the tests to run; ``run_path`` runs it as a
user's run and reads its ``run-summary.json``. ``missing_paths`` lists a device-dependent hold without a path: a new
reason to skip needs its fault before it lands (``tests/test_false_pass_matrix.py``).
"""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path

from encoder_conformance.coverage import Hold
from encoder_conformance.paths import CONTENT_ROOT, SUITES_DIR
from encoder_conformance.run_summary import SUMMARY_FILE
from encoder_conformance.runs.fault_matrix import matrix_env
from encoder_conformance.runs.suite_runner import run_pytest
from encoder_conformance.sim.process import start_simulator

#: the verdicts a run that took a hold may end in (PASS and PASS WITH WARNINGS would be false passes)
NOT_A_PASS = frozenset({"FAIL", "INCOMPLETE"})


@dataclass(frozen=True)
class FalsePassPath:
    """A twin fault that makes a check end with ``hold``, and the tests that take it."""

    hold: Hold
    fault: str  # a fault or conformant variant of the twin (``--sim-fault``)
    module: str  # the suite module (without .py)
    select: str  # pytest -k: the tests that take the path
    profile: str = "wachendorff-wdga-mt"
    external: bool = False  # the twin as a bench device (its own process, no bench stimulus): a real bench's path


#: a self-test profile with a writable 1019h and no manual's word on the SYNC-length EMCY (only an inferred rule says
#: a SYNC of the wrong length raises one): on a bench without an error stimulus, the EMCY tests' trigger
FULL_PDO_PROFILE = str(CONTENT_ROOT / "tests" / "data" / "profiles" / "cia406-full-pdo.yaml")

PATHS: tuple[FalsePassPath, ...] = (
    FalsePassPath(Hold.PERSISTENT_ERROR, "device_error_at_start", "test_nmt", "test_pdo_in_operational"),
    FalsePassPath(Hold.NO_TPDO_ON_CHANGE, "change_of_state_ignored", "test_pdo_comm",
                  "test_tpdo_silent_after_leaving_operational"),
    FalsePassPath(Hold.NO_EMCY_FROM_TRIGGER, "sync_length_error_silent", "test_emcy", "test_emcy_frame_on_error",
                  FULL_PDO_PROFILE, external=True),
    FalsePassPath(Hold.EMCY_NOT_REPEATED, "emcy_only_first", "test_emcy", "test_emcy_inhibit_time_spaces_emcys"),
    FalsePassPath(Hold.NO_USABLE_TPDO, "tpdo_mappings_empty", "test_pdo_comm", "test_tpdo_silent_after_leaving"),
    FalsePassPath(Hold.NO_READABLE_LONG_ENTRY, "long_reads_refused", "test_sdo_protocol",
                  "test_segmented_upload_wrong_toggle_aborts", "cia406-c3-st"),
    FalsePassPath(Hold.VALUES_CHANGED, "mapped_values_change_every_read", "test_pdo_mapping",
                  "test_mapping_procedure_payload_matches_sdo"),
)


def missing_paths(paths: tuple[FalsePassPath, ...] = PATHS) -> list[Hold]:
    """The holds a device can cause that no path covers (each needs a twin fault that takes it)."""
    covered = {path.hold for path in paths}
    return [hold for hold in Hold if hold.device_dependent and hold not in covered]


@dataclass
class PathResult:
    """What one path's run ended in."""

    path: FalsePassPath
    overall: str
    exit_code: int
    holds: dict[str, int] = field(default_factory=dict)  # hold name -> checks it kept from judging

    @property
    def taken(self) -> bool:
        """The fault made a check end with the path's hold (the path was exercised, not only the run failed)."""
        return self.holds.get(self.path.hold.name, 0) > 0

    @property
    def ok(self) -> bool:
        """The path was taken and the run is no pass."""
        return self.taken and self.overall in NOT_A_PASS

    def line(self) -> str:
        taken = "taken" if self.taken else "NOT taken"
        return (f"{self.path.hold.name:24s} {self.path.fault:34s} {taken:9s} {self.overall:18s} exit {self.exit_code}"
                f"{'' if self.ok else '   <-- false PASS or path not exercised'}")


def run_path(path: FalsePassPath, workdir: Path, extra: tuple[str, ...] = ()) -> PathResult:
    """One run of the path's tests against the twin with its fault, judged as a user's run is."""
    folder = workdir / f"{path.hold.name.lower()}-{path.fault}"
    command = [str(SUITES_DIR / f"{path.module}.py"), "-q", "-p", "no:cacheprovider", "--tb=no",
               "--ec-profile", path.profile, "--ec-report-dir", str(folder), "--ec-history", "off",
               "-k", path.select, *extra]
    env = matrix_env()
    with ExitStack() as stack:
        if path.external:  # a device on a bus: no --sim-fault, no bench error stimulus
            folder.mkdir(parents=True, exist_ok=True)
            twin = start_simulator(path.profile, faults=[path.fault], log_path=folder / "twin.log")
            stack.callback(twin.stop)
            command += ["--ec-can-interface", "remote", "--ec-can-channel", twin.can_url]
        else:
            command += ["--ec-sim-fault", path.fault]
        completed = run_pytest(command, CONTENT_ROOT, folder / "pytest-output.txt", timeout=600, env=env)
    summary_path = folder / SUMMARY_FILE
    if not summary_path.exists():
        raise RuntimeError(f"no {SUMMARY_FILE} from pytest {' '.join(command)}:\n{completed.output[-4000:]}")
    data = json.loads(summary_path.read_text(encoding="utf-8"))
    return PathResult(path, str(data["overall"]), completed.returncode, dict(data["coverage"]["holds"]))


def run_matrix(workdir: Path, paths: tuple[FalsePassPath, ...] = PATHS, workers: int = 2) -> list[PathResult]:
    """Every path, ``workers`` runs at a time."""
    with ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(lambda path: run_path(path, workdir), paths))
