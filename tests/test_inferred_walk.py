"""Rules we only inferred never fail a device unless --strict-inferred (issue 26): a walk over every test marked
inferred.

Each fault the suites can only see through an inferred rule (``fault_catalogue.JUDGED_STRICTLY``) runs against its
own suite modules twice: as a user's run (no test may end failed: the broken inferred rules are warnings) and with
--strict-inferred (the same tests fail). A static check keeps the walk complete: every suite test whose verdict
rests on ``inferred`` (``evidence.rests_on("inferred", ...)``, directly or through a helper of its module) is warned
by the walk, and the places that choose the basis at run time are the known ones.
"""

from __future__ import annotations

import ast
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from encoder_conformance.paths import CONTENT_ROOT, SUITES_DIR
from encoder_conformance.plugin import suite_helpers
from encoder_conformance.plugin.verdicts import STRICT_OPTION
from encoder_conformance.run_summary import RunSummary
from encoder_conformance.runs.fault_matrix import matrix_env
from encoder_conformance.runs.suite_runner import SessionResult, run_pytest
from encoder_conformance.sim.fault_catalogue import JUDGED_STRICTLY, TARGET_MODULES
from tests.suite_session import FaultRuns

PROFILE = "wachendorff-wdga-mt"
#: the suites' helpers beside their modules (a basis chosen there counts as the suites')
SUITE_HELPERS_DIR = Path(suite_helpers.__file__).parent
#: faults whose tests need what the WDGA lacks (a writable 1019h)
PROFILE_OF = {"sync_length_unchecked": "tests/data/profiles/cia406-full-pdo.yaml",
              "sync_length_error_silent": "tests/data/profiles/cia406-full-pdo.yaml"}
#: tests that may rest on inferred but assert nothing there: what breaks only an inferred rule is noted or
#: recorded as a problem (a warning), which the walk's faults need not show again
NO_INFERRED_ASSERTION = {
    "test_cam::test_low_limit_above_high_limit": "the inferred branch (_observe_low_above_high) only notes the states",
    "test_value_domain::test_write_outside_declared_domain_is_refused": "a probe only our inference refuses is a "
                                                                       "recorded problem; asserts are firm probes'",
}
#: the places that take a verdict's basis from data at run time, and the test the walk covers through each
DYNAMIC_BASIS = {
    "cam::Findings": "CAM checks (plugin/suite_helpers/cam.py): the inferred cams are recorded problems (walked by "
                     "cam_edge_off_by_one)",
    "test_emcy::_bus_trigger": "test_emcy::test_emcy_on_sync_length",
}


def _session(fault: str, strict: bool, workdir: Path, fault_runs: FaultRuns) -> tuple[Path, SessionResult]:
    """One targeted run of ``fault``: its report folder and how it ended. A --strict-inferred run on the main
    profile is the fault matrix's run of that fault (the same command: its modules, --strict-inferred)."""
    profile = PROFILE_OF.get(fault, PROFILE)
    if strict and profile == PROFILE:
        return fault_runs(PROFILE, fault)
    folder = workdir / f"{fault}-{'strict' if strict else 'default'}"
    command = [*(str(SUITES_DIR / f"{m}.py") for m in TARGET_MODULES[fault]), "-q", "-p", "no:cacheprovider",
               "--ec-profile", str(CONTENT_ROOT / profile) if "/" in profile else profile,
               "--ec-report-dir", str(folder), "--tb=no", "--ec-history", "off", "--ec-sim-fault", fault,
               *([STRICT_OPTION] if strict else [])]
    # the matrix's environment, as the shared runs: the same hypothesis examples with and without strict
    return folder, run_pytest(command, CONTENT_ROOT, folder / "pytest-output.txt", timeout=600, env=matrix_env())


def _run(fault: str, strict: bool, workdir: Path, fault_runs: FaultRuns) -> dict[str, str]:
    """One targeted run of ``fault``: test name -> failed / error / warning (passed and skipped left out)."""
    folder, result = _session(fault, strict, workdir, fault_runs)
    junit = folder / "junit.xml"
    assert junit.exists(), result.output[-3000:]
    stopped = RunSummary.read(folder).could_not_test
    assert stopped is None, f"{fault}: the run did not test the device: {stopped}\n{result.output[-3000:]}"
    outcomes = {}
    for case in ET.parse(junit).getroot().iter("testcase"):
        name = f"{case.get('classname', '').split('.')[-1]}::{case.get('name', '').split('[')[0]}"
        props = {p.get("name"): p.get("value") for p in case.iter("property")}
        if case.find("failure") is not None or case.find("error") is not None:
            outcomes[name] = "failed" if props.get("verdict_basis") == "inferred" else "failed elsewhere"
        elif props.get("verdict") == "warning":
            outcomes.setdefault(name, "warning")
    return outcomes


#: its sessions run ahead (tests/runs_ahead.py): the foreground keeps no slot of the background's
FOREGROUND_SLOTS = 0


def sessions_ahead(runs) -> dict:
    """Every strictly judged fault, without and with --strict-inferred (the strict runs on the main profile shared
    with the fault matrix, tests/suite_session.py)."""
    workdir = runs.mktemp("inferred-walk")
    return {("inferred-walk", fault, strict): lambda f=fault, s=strict: _run(f, s, workdir, runs.fault_runs)
            for fault in sorted(JUDGED_STRICTLY) for strict in (False, True)}


@pytest.fixture(scope="module")
def walk(runs_ahead) -> dict[tuple[str, bool], dict[str, str]]:
    """(fault, strict) -> its outcomes (a few runs at a time, most ahead)."""
    return {(fault, strict): outcomes for (_, fault, strict), outcomes
            in runs_ahead.results(sessions_ahead(runs_ahead)).items()}


def test_no_inferred_rule_fails_a_device_without_strict(walk):
    failed = {f"{fault}: {test}": outcome for (fault, strict), outcomes in walk.items() if not strict
              for test, outcome in outcomes.items() if outcome == "failed"}
    assert failed == {}, "tests that failed on a rule we only inferred, without --strict-inferred"


def test_with_strict_the_warned_tests_fail(walk):
    for fault in JUDGED_STRICTLY:
        warned = {t for t, o in walk[(fault, False)].items() if o == "warning"}
        assert warned, f"{fault}: no test warned (the walk sees no inferred rule broken)"
        strict = walk[(fault, True)]
        assert {t for t in warned if strict.get(t) != "failed"} == set(), f"{fault}: warned, but not failed strictly"


def test_the_known_victims_warn(walk):
    """Issue 26: two tests whose verdict rests on inferred failed the devices they judged."""
    assert walk[("open_transfer_blocks_requests", False)].get(
        "test_sdo_protocol::test_transfer_left_open_does_not_block_the_server") == "warning"
    assert walk[("sync_length_unchecked", False)].get("test_emcy::test_emcy_on_sync_length") == "warning"


def _name(func: ast.expr) -> str | None:
    return func.attr if isinstance(func, ast.Attribute) else func.id if isinstance(func, ast.Name) else None


def _basis_calls(node: ast.AST) -> list[ast.Call]:
    return [c for c in ast.walk(node) if isinstance(c, ast.Call) and _name(c.func) == "rests_on" and c.args]


def _constants(expr: ast.expr) -> set[str]:
    """The string constants a basis argument may take ("cia" if ... else "manual": both)."""
    return {n.value for n in ast.walk(expr) if isinstance(n, ast.Constant) and isinstance(n.value, str)}


def _declares(node: ast.AST, tops: dict[str, ast.AST], seen: tuple[str, ...] = ()) -> bool:
    """``node`` rests a verdict on "inferred", itself or through a helper (not a test) of its module."""
    if any("inferred" in _constants(c.args[0]) for c in _basis_calls(node)):
        return True
    called = {_name(c.func) for c in ast.walk(node) if isinstance(c, ast.Call)}
    return any(_declares(tops[n], tops, (*seen, n)) for n in called
               if n in tops and n not in seen and not n.startswith("test_"))


def _declaring_tests() -> tuple[set[str], set[str]]:
    """(tests resting on a literal "inferred", directly or through a helper of their module; the top-level
    functions and classes, of the suites and of plugin/suite_helpers/, that pass a basis taken from data at run
    time)."""
    tests, dynamic = set(), set()
    for path in [*sorted(SUITES_DIR.glob("test_*.py")), *sorted(SUITE_HELPERS_DIR.glob("*.py"))]:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        tops: dict[str, ast.AST] = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef | ast.ClassDef)}
        for name, node in tops.items():
            if name.startswith("test_") and _declares(node, tops):
                tests.add(f"{path.stem}::{name}")
            if any(not _constants(c.args[0]) for c in _basis_calls(node)):  # a name, a starred tuple
                dynamic.add(f"{path.stem}::{name}")
    return tests, dynamic


def test_every_test_resting_on_inferred_is_walked(walk):
    tests, dynamic = _declaring_tests()
    assert dynamic == set(DYNAMIC_BASIS), "a new place chooses the basis at run time: add it to DYNAMIC_BASIS"
    walked = {t for (_, strict), outcomes in walk.items() if not strict for t, o in outcomes.items() if o == "warning"}
    named = {v for v in DYNAMIC_BASIS.values() if v.startswith("test_")}
    missing = sorted((tests | named) - walked - set(NO_INFERRED_ASSERTION))
    assert missing == [], "tests resting on inferred that no fault of JUDGED_STRICTLY makes warn"
