"""The library passes the type checker (mypy, configured in pyproject.toml's [tool.mypy]).

Every ``type: ignore`` left in the library names its error code and says why (``# why: ...``);
mypy's warn_unused_ignores fails one that is no longer needed.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
TIMEOUT_S = 120  # a cold run takes about 5 s, one with mypy's cache (.mypy_cache/) under 1 s


def test_the_library_passes_mypy():
    if importlib.util.find_spec("mypy") is None:
        pytest.skip("mypy is not installed (pip install -e '.[dev]')")
    done = subprocess.run([sys.executable, "-m", "mypy"], cwd=REPO, capture_output=True, text=True,
                          timeout=TIMEOUT_S, check=False)
    assert done.returncode == 0, f"mypy failed (exit {done.returncode}):\n{done.stdout}{done.stderr}"
