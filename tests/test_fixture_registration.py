"""The suites' fixtures cannot be shadowed (issue 41): the modules of the top-level fixtures/ folder are registered
as ``encoder_conformance.plugin.fixtures.*`` (the package's own name), not as ``fixtures.*``, which the PyPI
distribution ``fixtures`` (or any package of that name imported or found first) would take."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from encoder_conformance.paths import CONTENT_ROOT

REPO = Path(__file__).resolve().parents[1]
#: a stand-in for the PyPI distribution ``fixtures`` (testing-cabal's): a package of that name with none of our modules
SHADOW = '"""Not the suites\' fixtures: a package that took the name first, as PyPI\'s fixtures would."""\n' \
         "class Fixture:\n    pass\n"


def _shadow(tmp_path: Path) -> dict[str, str]:
    """An environment whose sys.path finds a ``fixtures`` package before the checkout's folder."""
    (tmp_path / "shadow" / "fixtures").mkdir(parents=True)
    (tmp_path / "shadow" / "fixtures" / "__init__.py").write_text(SHADOW, encoding="utf-8")
    environ = {k: v for k, v in os.environ.items() if not k.startswith(("CAN_", "PYTEST_"))}
    return {**environ, "PYTHONPATH": os.pathsep.join([str(tmp_path / "shadow"), str(REPO)])}


def test_the_fixture_modules_are_the_folders_under_the_packages_name():
    """``encoder_conformance.plugin.fixtures.bus`` is the file fixtures/bus.py of the content root (checkout or
    wheel), and conftest.py registers every module of the folder, under that name only."""
    from encoder_conformance.plugin.fixtures import bus

    assert Path(bus.__file__ or "") == CONTENT_ROOT / "fixtures" / "bus.py"
    conftest = (CONTENT_ROOT / "conftest.py").read_text(encoding="utf-8")
    modules = sorted(path.stem for path in (CONTENT_ROOT / "fixtures").glob("*.py") if path.stem != "__init__")
    assert sorted(line.strip().strip('",').rpartition(".")[2] for line in conftest.splitlines()
                  if "encoder_conformance.plugin.fixtures." in line) == modules
    assert '"fixtures.' not in conftest


def test_a_package_named_fixtures_first_does_not_hide_the_suites_fixtures(tmp_path):
    """With a ``fixtures`` package first on sys.path and imported before the conftest (``-p fixtures``, as a
    plugin of another distribution might), the suites' fixtures are still found and a test runs; under the old
    name the same environment could not import them."""
    env = _shadow(tmp_path)
    old_name = subprocess.run([sys.executable, "-c", "import fixtures, fixtures.bus"], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=60)
    assert "No module named 'fixtures.bus'" in old_name.stderr  # the shadow wins the old name
    done = subprocess.run(
        [sys.executable, "-m", "pytest", str(REPO / "suites" / "test_identity.py"), "-q", "-p", "no:cacheprovider",
         "-p", "fixtures", "--ec-sim-inprocess", "--ec-profile", "waycon-sx", "--ec-history", "off",
         "--ec-report-dir", str(tmp_path / "report")],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert " passed" in done.stdout, done.stdout[-2000:]
