"""The package outside the checkout: the built wheel, installed into a fresh virtual environment and used
from an empty folder, runs the shipped suites against a shipped profile and the user's own profile.

One module fixture builds the wheel and installs it (its dependencies come from the package index, as on a
firmware team's CI runner); the tests then run the installed command in folders of their own.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import venv
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
OWN_PROFILE = """\
schema_version: 1
id: my-encoder
title: My own variant of the WDGA multiturn
extends: wachendorff-wdga-mt
"""


def _run(command: list[str], cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PYTHON", "VIRTUAL_ENV", "PYTEST", "ENCODER_CONFORMANCE"))}
    return subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def _install(root: Path) -> Path:
    """The bin/ folder of a fresh virtual environment under ``root`` with the built wheel installed."""
    built = _run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", str(root / "dist"),
                  str(REPO)], cwd=root)
    assert built.returncode == 0, built.stderr
    wheel = next((root / "dist").glob("encoder_conformance-*.whl"))
    venv.create(root / "venv", with_pip=True)
    bin_dir = root / "venv" / "bin"
    done = _run([str(bin_dir / "python"), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                 str(wheel)], cwd=root, timeout=600)
    if done.returncode != 0 and "Could not find a version" in done.stderr + done.stdout:
        pytest.skip(f"the package index cannot be reached from here: {done.stderr.strip()[-200:]}")
    assert done.returncode == 0, done.stderr
    return bin_dir


def work_ahead(runs) -> dict:
    """The wheel's build and install (tests/runs_ahead.py): pip's half-minute, beside the other modules."""
    return {("wheel",): lambda: _install(runs.mktemp("wheel"))}


@pytest.fixture(scope="module")
def installed(runs_ahead) -> Path:
    """The bin/ folder of a fresh virtual environment with the built wheel installed (made ahead where it can be)."""
    return runs_ahead.results(work_ahead(runs_ahead))[("wheel",)]


def test_the_wheel_carries_suites_fixtures_and_profiles(installed):
    """The suites, fixtures and shipped profiles are inside the installed package, not only in the checkout."""
    found = _run([str(installed / "python"), "-c",
                  "from encoder_conformance import paths; print(paths.IN_CHECKOUT, paths.SUITES_DIR)"],
                 cwd=installed)
    in_checkout, suites = found.stdout.split()
    assert in_checkout == "False"
    assert (Path(suites) / "test_nmt.py").is_file()
    assert (Path(suites).parent / "device_profiles" / "wachendorff-wdga-mt.yaml").is_file()
    assert (Path(suites).parent / "fixtures" / "bus.py").is_file()


def test_a_shipped_profile_runs_from_an_empty_folder(installed, tmp_path):
    """`encoder-conformance run --profile wachendorff-wdga-mt` writes its report into the folder it runs in."""
    done = _run([str(installed / "encoder-conformance"), "run", "--profile", "wachendorff-wdga-mt",
                 "-k", "identity or heartbeat"], cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    summaries = list((tmp_path / "reports").glob("*/run-summary.json"))
    assert len(summaries) == 1
    summary = json.loads(summaries[0].read_text(encoding="utf-8"))
    assert summary["profile_id"] == "wachendorff-wdga-mt"
    assert (summaries[0].parent / "report.html").is_file()
    assert (tmp_path / "reports" / "history.sqlite").is_file()


def test_the_users_own_profile_extends_a_shipped_one(installed, tmp_path):
    """`--profile ./my-encoder.yaml` (extending a shipped profile) runs, and `profile list` shows both."""
    (tmp_path / "my-encoder.yaml").write_text(OWN_PROFILE, encoding="utf-8")
    listing = _run([str(installed / "encoder-conformance"), "profile", "list"], cwd=tmp_path)
    assert listing.returncode == 0, listing.stderr
    ids = [line.split()[0] for line in listing.stdout.splitlines() if line.strip()]
    assert "wachendorff-wdga-mt" in ids
    assert "my-encoder" in ids
    done = _run([str(installed / "encoder-conformance"), "run", "--profile", "./my-encoder.yaml",
                 "--history", "off", "-k", "identity"], cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    summary = json.loads(next((tmp_path / "reports").glob("*/run-summary.json")).read_text(encoding="utf-8"))
    assert summary["profile_id"] == "my-encoder"


def test_pytest_finds_the_plugin_through_its_entry_point(installed, tmp_path):
    """Outside the checkout no conftest.py declares the options: the pytest11 entry point does."""
    done = _run([str(installed / "python"), "-m", "pytest", "--help"], cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "--ec-profile" in done.stdout


def test_the_wheel_carries_the_example_pipelines(installed, tmp_path):
    for name in ("github", "gitlab"):
        done = _run([str(installed / "encoder-conformance"), "firmware-ci", "--example", name], cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        assert "encoder-conformance firmware-ci --simulator" in done.stdout


def test_the_pypi_fixtures_package_does_not_hide_the_suites_fixtures(installed, tmp_path):
    """PyPI's ``fixtures`` installed beside the wheel and imported first (``-p fixtures``, as another plugin
    might): the bundled suites still find their fixtures (registered as encoder_conformance.plugin.fixtures.*)."""
    added = _run([str(installed / "python"), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                  "fixtures"], cwd=tmp_path, timeout=300)
    if added.returncode != 0 and "Could not find a version" in added.stderr + added.stdout:
        pytest.skip(f"the package index cannot be reached from here: {added.stderr.strip()[-200:]}")
    assert added.returncode == 0, added.stderr
    where = _run([str(installed / "python"), "-c",
                  "import fixtures; from encoder_conformance import paths; print(fixtures.__file__, paths.SUITES_DIR)"],
                 cwd=tmp_path)
    pypi_fixtures, suites = where.stdout.split()
    assert "site-packages" in pypi_fixtures
    assert "bundled" not in pypi_fixtures
    done = _run([str(installed / "python"), "-m", "pytest", str(Path(suites) / "test_identity.py"), "-p", "fixtures",
                 "-q", "--ec-profile", "waycon-sx", "--ec-history", "off", "--ec-report-dir", str(tmp_path / "r")],
                cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert " passed" in done.stdout
