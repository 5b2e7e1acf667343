"""Every device profile's simulated twin passes the full suite; a wrong profile fails on identity.

Each run is a pytest session in its own process (forked from a pre-loaded server: suite_runner) against the
simulator in its own process, as `encoder-conformance run --profile ID` runs it. Run times are printed for
the notes.
"""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from encoder_conformance.profile.loader import iter_profile_ids, load_profile
from tests.suite_session import PARALLEL_RUNS, REPO, run_suite

#: every shipped profile, and the self-test variants with the optional PDO features none of them has (inhibit
#: time, SYNC start value, 1019h, dummy mapping) and with SDO block transfer, so that those checks pass against
#: a conformant twin too
PROFILES = [ref.id for ref in iter_profile_ids() if not ref.abstract] + [
    str(REPO / "tests" / "data" / "profiles" / name) for name in ("cia406-full-pdo.yaml", "cia406-block-sdo.yaml")]


def _expected_cost(profile_id: str) -> float:
    """Boot-up delay dominates a run (every reset waits for it): start the slow twins first."""
    return load_profile(profile_id).profile.simulator.bootup_delay_ms


#: its sessions run ahead (tests/runs_ahead.py): the foreground keeps no slot of the background's
FOREGROUND_SLOTS = 0


def sessions_ahead(runs) -> dict:
    """Each profile's full run, the slow twins first."""
    return {("full", p): lambda p=p: runs.full_runs(p) for p in sorted(PROFILES, key=_expected_cost, reverse=True)}


@pytest.fixture(scope="module")
def twin_runs(full_runs):
    """One full suite run per profile against its own twin (a few in parallel); the session's runs
    (tests/suite_session.py): the WDGA's was run already for the fault matrix's baseline."""
    def one(profile: str):
        run = full_runs(profile)
        return profile, run.folder, run.completed, run.seconds

    with ThreadPoolExecutor(max_workers=PARALLEL_RUNS) as pool:
        ordered = sorted(PROFILES, key=_expected_cost, reverse=True)
        results = {profile: rest for profile, *rest in pool.map(one, ordered)}
    return results


def _own_seconds(folder: Path) -> tuple[float, float]:
    """A run's wall time as the run itself measured it (its process, not the wait for a session slot) and what of
    it the host's load added (run-summary.json time_budget: wall_s, and host_wait_s, the test thread ready to run
    while the host ran something else; 0 where the platform does not say)."""
    budget = json.loads((folder / "report" / "run-summary.json").read_text(encoding="utf-8"))["time_budget"]
    return budget["wall_s"], budget.get("host_wait_s") or 0.0


def test_each_full_run_takes_well_under_a_minute(twin_runs, capsys):
    """Prints each profile's run time, the host's share of it and the pytest summary; every run's own time (its
    process's wall time less what the host's load added) stays under 60 s. The runs share the host with the other
    self-tests and wait for a session slot: the harness's clock says as much about that as about the suite (seen:
    62-83 s for runs whose processes took 44-46 s)."""
    own = {}
    with capsys.disabled():
        print("\nfull suite against each twin (run time, of it waiting for the host, pytest summary):")
        for profile, (folder, completed, _) in sorted(twin_runs.items()):
            wall, waited = _own_seconds(folder)
            own[profile] = wall - waited
            last = (completed.output.strip().splitlines() or ["(no output)"])[-1]
            print(f"  {Path(profile).stem:32s} {wall:5.1f} s {waited:5.1f} s  {last}")
    slow = {p: round(s) for p, s in own.items() if s >= 60}
    assert not slow, f"runs of a minute or more of their own time: {slow}"


@pytest.mark.parametrize("profile", PROFILES, ids=lambda profile: Path(profile).stem)
def test_twin_passes_its_profile(profile, twin_runs):
    folder, completed, _ = twin_runs[profile]
    assert completed.returncode == 0, f"{profile} twin fails its own profile:\n{completed.output[-4000:]}"
    assert (folder / "report" / "report.html").exists()
    assert (folder / "report" / "junit.xml").exists()
    assert not (folder / "report" / "allure-results").exists(), "allure results are written only with --allure"


def test_wrong_profile_fails_on_identity_without_timeouts(tmp_path):
    """The WV58M twin checked with the WDGA profile: one clear identity reason, fast, non-zero exit."""
    completed, seconds = run_suite(tmp_path, "--ec-profile", "wachendorff-wdga-mt",
                                   "--ec-sim-profile", "siko-wx58m-1212-mt")
    assert completed.returncode != 0
    assert "wrong device for profile wachendorff-wdga-mt" in completed.output
    assert "0x00000195" in completed.output  # the vendor-id the device really reports
    assert "No SDO response" not in completed.output
    assert seconds < 30, f"wrong-profile run took {seconds:.0f} s; expected a fast, single-reason failure"


def test_allure_results_on_request(tmp_path):
    """--allure writes allure-pytest results (one result file per test) into the report folder."""
    completed, _ = run_suite(tmp_path, "--ec-profile", "waycon-sx", "-k", "test_identity", "--ec-allure")
    assert completed.returncode == 0, completed.output[-3000:]
    results = list((tmp_path / "report" / "allure-results").glob("*-result.json"))
    assert results, "no allure result files"
    # the fork server imported these before the session on purpose: pytest's warning about them is filtered
    assert "PytestAssertRewriteWarning" not in completed.output, completed.output[-2000:]
