"""Run the suites against every conformant variant of the twin: a reading the texts allow must never fail.

Each open reading (``readings``) has a variant of the twin that plays it. The variant matrix runs the
suite modules each reading concerns against its variant, on every profile where it applies (the
profile has the capabilities the reading needs and no quirk whose documented behaviour the variant
would break). A conformant variant that fails a test means the suite accepts only one reading: a false
failure waiting for a real device. Warnings (broken inferred rules) are allowed; failures and errors
are not, and every run must have judged at least one test (a variant that only skips proves nothing).
"""

from __future__ import annotations

from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from encoder_conformance.cia.cia301 import COB_ID_INVALID, PDO_MAPPING_OFFSET
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.open_points import OpenReading, all_readings
from encoder_conformance.paths import CONTENT_ROOT
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.schema import DeviceProfile, resolve_node_id_expression
from encoder_conformance.runs.fault_matrix import PREFLIGHT, RunResult, run_suite
from encoder_conformance.sim.twin import overridden_methods  # imports the twin's engine when called

#: one profile per family, the generic class C3 and the self-test profiles with the optional features
#: (inhibit time, SYNC start value, block transfer) no shipped device has
REPRESENTATIVE_PROFILES: tuple[str, ...] = (
    "wachendorff-wdga-mt",
    "faulhaber-mc5005",
    "fraba-posital-awc58-c2-mt",
    "siko-wx58m-1212-mt",
    "waycon-sx",
    "cia406-c3-st",
    "tests/data/profiles/cia406-full-pdo.yaml",
    "tests/data/profiles/cia406-block-sdo.yaml",
    "tests/data/profiles/cia406-empty-tpdo1.yaml",
)
#: the class C3 encoder with block transfer and the C2 encoder with TPDO1 delivered invalid and empty: for any
#: other reading they repeat the profile they are made from
ONLY_WHERE_NEEDED: frozenset[str] = frozenset({"tests/data/profiles/cia406-block-sdo.yaml",
                                               "tests/data/profiles/cia406-empty-tpdo1.yaml"})
#: a pseudo-capability of a profile with a TPDO delivered invalid (18xxh sub 1 bit 31) that maps nothing
EMPTY_INVALID_TPDO = "tpdo_delivered_invalid_and_empty"


@dataclass(frozen=True)
class VariantRun:
    """One variant against one profile, and what came of it."""

    reading: OpenReading
    profile: str
    result: RunResult

    @property
    def bad(self) -> list[str]:
        """Tests that failed, errored or broke our own code (the start-up check included)."""
        return sorted(name for name, outcome in self.result.outcomes.items()
                      if outcome in ("failed", "error", "internal"))

    @property
    def judged(self) -> int:
        """Tests that reached a verdict (passed, failed or errored), the start-up check aside."""
        return sum(1 for name, outcome in self.result.outcomes.items() if name != PREFLIGHT and outcome != "skipped")

    @property
    def expected_exit(self) -> int:
        """The exit code the reading's verdict gives: 0 for PASS, 6 where the reading keeps checks from running."""
        return RunExit.INCOMPLETE if self.reading.verdict == "INCOMPLETE" else RunExit.PASSED

    @property
    def ok(self) -> bool:
        return not self.bad and self.judged > 0 and self.result.returncode == self.expected_exit


def _profile_ref(profile: str) -> str:
    return str(CONTENT_ROOT / profile) if "/" in profile else profile


def applicable(profile: str, readings: list[OpenReading] | None = None) -> list[OpenReading]:
    """The readings a profile can play: its capabilities cover what each needs, no quirk excludes it."""
    loaded = load_profile(_profile_ref(profile)).profile
    capabilities = {name for name, value in loaded.capabilities if value}
    capabilities |= {f"lss:{service}" for service in loaded.capabilities.lss}
    if _has_empty_invalid_tpdo(loaded):
        capabilities.add(EMPTY_INVALID_TPDO)
    return [r for r in (readings or all_readings()) if r.applies_to(capabilities, loaded.effects)]


def _has_empty_invalid_tpdo(profile: DeviceProfile) -> bool:
    """A TPDO whose COB-ID default has bit 31 set and whose mapping's sub 0 defaults to 0."""
    for comm in (i for i in profile.objects if 0x1800 <= i <= 0x19FF):
        cob, count = profile.entry(comm, 1), profile.entry(comm + PDO_MAPPING_OFFSET, 0)
        cob_id = resolve_node_id_expression(cob.default, 1) if cob is not None else None
        if isinstance(cob_id, int) and cob_id & COB_ID_INVALID and count is not None and count.default == 0:
            return True
    return False


def plan(profiles: tuple[str, ...] = REPRESENTATIVE_PROFILES,
         readings: list[OpenReading] | None = None) -> list[tuple[OpenReading, str]]:
    """(reading, profile) for every profile where each reading applies; a profile in ONLY_WHERE_NEEDED only for
    the readings no other profile of the list can play."""
    others = [p for p in profiles if p not in ONLY_WHERE_NEEDED]
    played = {reading.point for profile in others for reading in applicable(profile, readings)}
    pairs = []
    for profile in profiles:
        pairs += [(reading, profile) for reading in applicable(profile, readings)
                  if profile not in ONLY_WHERE_NEEDED or reading.point not in played]
    return pairs


def combine(pairs: list[tuple[OpenReading, str]]) -> list[tuple[str, list[OpenReading]]]:
    """The pairs as runs: per profile, readings whose variants override no method in common share one twin
    (and one run of the union of their modules). Readings of different points are independent choices, so a
    conformant device may take them all at once; a variant whose method another one overrides would be hidden
    behind it, so those two never share a twin, and neither does a reading that says it hides others
    (``shares_twin``)."""
    runs: list[tuple[str, list[OpenReading], set[tuple[str, str]]]] = []
    for reading, profile in pairs:
        taken = overridden_methods(reading.variant)
        home = next((run for run in runs if run[0] == profile and not run[2] & taken
                     and reading.shares_twin and all(r.shares_twin for r in run[1])), None)
        if home is None:
            runs.append((profile, [reading], set(taken)))
        else:
            home[1].append(reading)
            home[2].update(taken)
    return [(profile, readings) for profile, readings, _ in runs]


def _restricted(result: RunResult, modules: tuple[str, ...]) -> RunResult:
    """The outcomes of ``result`` in ``modules`` (and the start-up check, which every reading needs)."""
    outcomes = {name: outcome for name, outcome in result.outcomes.items()
                if name == PREFLIGHT or name.split("::")[0] in modules}
    return RunResult(result.fault, result.returncode, outcomes)


def run_variants(pairs: list[tuple[OpenReading, str]], workdir: Path, workers: int = 2) -> list[VariantRun]:
    """Each variant against its modules on its profile, ``workers`` suite sessions at a time.

    Variants that can share a twin (``combine``) run together, once (``run_shared``)."""
    with ThreadPoolExecutor(max_workers=workers) as pool:
        batches = list(pool.map(lambda run: run_shared(run[0], run[1], workdir), combine(pairs)))
    return in_plan_order(pairs, batches)


def run_shared(profile: str, readings: list[OpenReading], workdir: Path) -> list[VariantRun]:
    """The readings ``combine`` put on one twin, in one run; a shared run with a failure is run again one variant
    at a time, so that each failure is charged to the reading that shows it."""
    folder = workdir / Path(profile).stem
    folder.mkdir(parents=True, exist_ok=True)
    variants = tuple(r.variant for r in readings)
    result = run_suite(profile, variants[0], folder, targeted=True, together=variants[1:])
    shared = [VariantRun(r, profile, _restricted(result, r.modules)) for r in readings]
    if len(readings) == 1 or all(run.ok for run in shared):
        return shared
    return [VariantRun(r, profile, run_suite(profile, r.variant, folder, targeted=True)) for r in readings]


def in_plan_order(pairs: list[tuple[OpenReading, str]], batches: Iterable[list[VariantRun]]) -> list[VariantRun]:
    """The runs of ``run_shared``'s batches in the order of ``pairs``."""
    order = {(reading.point, profile): n for n, (reading, profile) in enumerate(pairs)}
    runs = [run for batch in batches for run in batch]
    return sorted(runs, key=lambda run: order[(run.reading.point, run.profile)])


def format_runs(runs: list[VariantRun]) -> str:
    """Text table: variant, profile, tests judged, what failed."""
    lines = [f"variant matrix ({len(runs)} runs: each open reading's variant on each profile where it applies)"]
    for run in runs:
        verdict = "ok" if run.ok else "FALSE FAILURE" if run.bad else f"NOT JUDGED (exit {run.result.returncode})"
        lines.append(f"  {run.reading.variant:36s} {Path(run.profile).stem:28s} {run.judged:4d} judged  {verdict}")
        lines += [f"      {name}" for name in run.bad[:10]]
    return "\n".join(lines)
