"""Every device profile's simulated twin passes the full suite; a wrong profile fails on identity.

Each run is a separate pytest process against the simulator in its own process, exactly as
`encoder-conformance run --profile ID` does it. Run times are printed for the notes.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from encoder_conformance.profile.loader import iter_profile_ids

REPO = Path(__file__).resolve().parents[1]
PROFILES = [ref.id for ref in iter_profile_ids() if not ref.abstract]


def run_suite(tmp_path: Path, *args: str) -> tuple[subprocess.CompletedProcess[str], float]:
    command = [sys.executable, "-m", "pytest", str(REPO / "suites"), "-q", "-p", "no:cacheprovider",
               "--tb=line", "--report-dir", str(tmp_path / "report"), *args]
    start = time.monotonic()
    completed = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=600)
    return completed, time.monotonic() - start


@pytest.mark.parametrize("profile", PROFILES)
def test_twin_passes_its_profile(profile, tmp_path, capsys):
    completed, seconds = run_suite(tmp_path, "--device-profile", profile)
    summary = completed.stdout.strip().splitlines()[-1] if completed.stdout.strip() else completed.stderr[-500:]
    with capsys.disabled():
        print(f"\n  {profile:32s} {seconds:5.1f} s  {summary}")
    assert completed.returncode == 0, f"{profile} twin fails its own profile:\n{completed.stdout[-4000:]}"
    assert (tmp_path / "report" / "report.html").exists()
    assert (tmp_path / "report" / "junit.xml").exists()
    assert any((tmp_path / "report" / "allure-results").iterdir())


def test_wrong_profile_fails_on_identity_without_timeouts(tmp_path):
    """The WV58M twin checked with the WDGA profile: one clear identity reason, fast, non-zero exit."""
    completed, seconds = run_suite(tmp_path, "--device-profile", "wachendorff-wdga-mt",
                                   "--sim-profile", "siko-wx58m-1212-mt")
    assert completed.returncode != 0
    assert "wrong device for profile wachendorff-wdga-mt" in completed.stdout
    assert "0x00000195" in completed.stdout  # the vendor-id the device really reports
    assert "No SDO response" not in completed.stdout
    assert seconds < 30, f"wrong-profile run took {seconds:.0f} s; expected a fast, single-reason failure"
