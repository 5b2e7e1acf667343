"""The suite's hypothesis profiles are loaded before hypothesis is first used, and hypothesis is imported only where
a test module uses it (plugin/hypothesis_profiles.py): ~0.2 s of start-up an acceptance run does not spend."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

from encoder_conformance.paths import SUITES_DIR
from encoder_conformance.plugin import hypothesis_profiles

REPO = Path(__file__).resolve().parents[1]

IMPORT_EACH = """
import importlib.util, sys
for path in sys.argv[1:]:
    name = "suite_" + path.rsplit("/", 1)[-1][:-3]
    spec = importlib.util.spec_from_file_location(name, path)
    sys.modules[name] = module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
print(sorted(name for name in sys.modules if name == "hypothesis"))
"""


def _imports_hypothesis(paths: list[Path]) -> bool:
    completed = subprocess.run([sys.executable, "-c", IMPORT_EACH, *map(str, paths)], cwd=REPO, capture_output=True,
                               text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr[-2000:]
    return "hypothesis" in completed.stdout


def test_only_the_listed_suite_modules_import_hypothesis():
    """A suite module outside SUITES_USING_HYPOTHESIS would import hypothesis before its profile was loaded: its
    settings objects would take hypothesis's defaults."""
    modules = sorted(SUITES_DIR.glob("test_*.py"))
    listed = [m for m in modules if m.name in hypothesis_profiles.SUITES_USING_HYPOTHESIS]
    assert len(listed) == len(hypothesis_profiles.SUITES_USING_HYPOTHESIS), "a listed module no longer exists"
    assert not _imports_hypothesis([m for m in modules if m not in listed])
    assert all(_imports_hypothesis([m]) for m in listed), "a listed module no longer uses hypothesis: drop it"


def test_a_module_that_may_use_hypothesis_loads_the_profile_first(monkeypatch):
    loaded: list[str] = []
    monkeypatch.setattr(hypothesis_profiles, "_LOADED", [])
    monkeypatch.setattr(hypothesis_profiles, "load", lambda: loaded.append("loaded") or "dev")
    hypothesis_profiles.before_import(SUITES_DIR / "test_identity.py")
    assert loaded == [], "a suite module that does not use hypothesis does not import it"
    hypothesis_profiles.before_import(SUITES_DIR / "test_sdo_fuzz.py")
    hypothesis_profiles.before_import(REPO / "tests" / "test_plugin.py")
    assert loaded == ["loaded", "loaded"], "a listed suite module and any module outside the suites load it"


def test_each_session_chooses_its_profile_again(monkeypatch):
    """A process may run several sessions (in-process pytest): each loads the profile its environment names."""
    seen: list[list[str]] = []
    monkeypatch.setattr(hypothesis_profiles, "_LOADED", ["ci"])
    monkeypatch.setattr(hypothesis_profiles, "load", lambda: seen.append(list(hypothesis_profiles._LOADED)) or "dev")
    config = SimpleNamespace(getoption=lambda name, default=None: default, option=SimpleNamespace(verbose=0))
    hypothesis_profiles.configure(config)  # hypothesis is imported in this process: the profile is loaded now
    assert seen == [[]], "the last session's profile is forgotten before this one's is loaded"
