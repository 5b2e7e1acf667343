"""Profiles drafted from EDS files nobody here wrote are trustworthy (issue 9).

For every EDS under tests/data/eds (public vendor files in vendors/, with their sources and licences in
vendors/SOURCES.md, and our own files that each show an oddity): `profile from-eds` gives a draft that
validates; the draft exports back to an EDS with every object's type, access and default; and the
simulated twin of the draft passes the conformance suites with no failure, judged by the draft as
``--probe`` corrects it against that twin.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from encoder_conformance.probe.session import ProbeOptions, probe_device
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.eds import export_eds, objects_from_eds, profile_draft_from_eds, write_profile_draft
from encoder_conformance.profile.loader import load_profile
from tests.sim_rig import twin_of
from tests.suite_session import SessionResult, run_suite

EDS_DIR = Path(__file__).parent / "data" / "eds"
CORPUS = sorted([*EDS_DIR.glob("*.eds"), *(EDS_DIR / "vendors").glob("*.eds")])
IDS = [path.stem for path in CORPUS]
#: files whose twin plays the stack they come from, not a fresh one: the variants it runs with. A sub 0 without
#: DefaultValue leaves a stack's ARRAY empty and its elements answer 08000024h (issue 40: the public CiA 406 sample
#: EDS, loaded by a C++ stack's slave, and our own file with the same faults)
TWIN_VARIANTS: dict[str, tuple[str, ...]] = {"inconsistent_arrays": ("empty_arrays",),
                                             "kacanopen-cia406-sample": ("empty_arrays",)}


def _draft_file(eds: Path, folder: Path) -> Path:
    draft, todos = profile_draft_from_eds(eds, eds.stem.lower())
    out = folder / f"{draft['id']}.yaml"
    write_profile_draft(draft, out, todos)
    return out


def test_corpus_has_a_dozen_vendor_files_of_several_classes():
    vendors = list((EDS_DIR / "vendors").glob("*.eds"))
    assert len(vendors) >= 12
    listed = (EDS_DIR / "vendors" / "SOURCES.md").read_text(encoding="utf-8")
    assert all(path.name in listed for path in vendors), "every vendor file names its source and licence"


@pytest.mark.parametrize("eds", CORPUS, ids=IDS)
def test_draft_validates_and_round_trips_through_to_eds(eds: Path, tmp_path: Path):
    profile = load_profile(str(_draft_file(eds, tmp_path))).profile
    assert profile.todo, "a draft lists what the EDS cannot tell as todo:"
    exported = export_eds(profile, tmp_path / f"{profile.id}-export.eds")
    back = objects_from_eds(exported)
    problems = []
    for index, sub, _, entry in profile.iter_entries():
        obj = back.get(index)
        again = None if obj is None else (obj["subs"].get(sub) if "subs" in obj else obj if sub == 0 else None)
        if again is None:
            problems.append(f"{index:04X}h.{sub:02X} missing after to-eds")
            continue
        if datatypes.canonical_name(again["type"]) != datatypes.canonical_name(entry.type):
            problems.append(f"{index:04X}h.{sub:02X} type {entry.type} -> {again['type']}")
        if again["access"] != entry.access:
            problems.append(f"{index:04X}h.{sub:02X} access {entry.access} -> {again['access']}")
        if again.get("default") != entry.default:
            problems.append(f"{index:04X}h.{sub:02X} default {entry.default!r} -> {again.get('default')!r}")
    assert not problems, f"{eds.name}: to-eds lost {len(problems)} fact(s): {problems[:10]}"


def _probed_draft_file(eds: Path, twin_profile: Path, folder: Path) -> Path:
    """The draft corrected by ``--probe`` against the twin of ``twin_profile`` (issue 28)."""
    profile = load_profile(twin_profile).profile
    with twin_of(profile, faults=TWIN_VARIANTS.get(eds.stem, ())) as twin:
        draft, todos = profile_draft_from_eds(eds, f"{eds.stem.lower()}-probed")
        result = probe_device(draft, todos, ProbeOptions(twin.bus, profile.bus.node_id, boot_timeout_s=6.0))
    assert result.restored, result.findings.put_back_failures
    out = folder / f"{draft['id']}.yaml"
    write_profile_draft(draft, out, result.todos)
    return out


def _draft_twin_run(eds: Path, folder: Path) -> SessionResult:
    """The suites against the twin of the draft the EDS gives, judged by that draft as the live probe corrected it
    (so the probe's corrections are tested too)."""
    plain = _draft_file(eds, folder)
    probed = _probed_draft_file(eds, plain, folder)
    variants = [arg for name in TWIN_VARIANTS.get(eds.stem, ()) for arg in ("--ec-sim-fault", name)]
    return run_suite(folder, "--ec-profile", str(probed), "--ec-sim-profile", str(plain), *variants)[0]


def sessions_ahead(runs) -> dict:
    """Each corpus file's draft twin run (tests/runs_ahead.py)."""
    return {("eds-corpus", eds.stem): lambda eds=eds: _draft_twin_run(eds, runs.mktemp(eds.stem)) for eds in CORPUS}


@pytest.fixture(scope="module")
def twin_runs(runs_ahead):
    """The suites against the twin of each draft (a few at a time, most made ahead)."""
    return {key[1]: completed for key, completed in runs_ahead.results(sessions_ahead(runs_ahead)).items()}


@pytest.mark.parametrize("name", IDS)
def test_twin_of_the_draft_passes_the_suites(name: str, twin_runs):
    completed = twin_runs[name]
    assert completed.returncode == 0, f"{name}: the twin of its own draft fails:\n{completed.output[-3000:]}"
    assert "draft profile:" in completed.output, "a run with a draft profile says so"
