"""Where the suite's parts are, and the profile a run uses when none is named.

The suites, fixtures and shipped profiles live beside the package in a checkout; an installed wheel carries a
copy of them inside the package (``bundled/``, copied at build time by setup.py), so the tool works outside the
checkout. ``CONTENT_ROOT`` is whichever of the two this installation has.
"""

from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
CHECKOUT_ROOT = PACKAGE_DIR.parent
BUNDLE_DIR = PACKAGE_DIR / "bundled"
#: the parts a wheel carries (folders and files of the repository's top level)
BUNDLED_FOLDERS = ("suites", "fixtures", "device_profiles")
BUNDLED_FILES = ("conftest.py", "pyproject.toml")


def _in_checkout() -> bool:
    return all((CHECKOUT_ROOT / folder).is_dir() for folder in BUNDLED_FOLDERS)


IN_CHECKOUT = _in_checkout()
#: the folder holding suites/, fixtures/, device_profiles/, conftest.py and pyproject.toml (the pytest rootdir)
CONTENT_ROOT = CHECKOUT_ROOT if IN_CHECKOUT else BUNDLE_DIR
SUITES_DIR = CONTENT_ROOT / "suites"
PROFILE_DIR = CONTENT_ROOT / "device_profiles"
#: the suites' pytest settings ([tool.pytest.ini_options]): given with -c, so that the rootdir and the test ids
#: are the same wherever the tool is installed
PYTEST_CONFIG = CONTENT_ROOT / "pyproject.toml"
#: the profile of a run that names none (the first of the five source devices)
DEFAULT_PROFILE = "wachendorff-wdga-mt"


def default_reports_dir() -> Path:
    """reports/ of the checkout, or of the current folder where the tool is installed from a wheel."""
    return CHECKOUT_ROOT / "reports" if IN_CHECKOUT else Path.cwd() / "reports"
