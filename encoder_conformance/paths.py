"""Where the repository's parts are, and the profile a run uses when none is named."""

from __future__ import annotations

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
SUITES_DIR = REPO_ROOT / "suites"
PROFILE_DIR = REPO_ROOT / "device_profiles"
#: the profile of a run that names none (the first of the five source devices)
DEFAULT_PROFILE = "wachendorff-wdga-mt"
