"""Build step pyproject.toml cannot declare: the wheel carries the suites, fixtures and shipped profiles.

They stay at the repository's top level (suites/, fixtures/, device_profiles/, conftest.py, pyproject.toml)
and are copied into ``encoder_conformance/bundled/`` of the wheel, where encoder_conformance/paths.py finds
them when the package is installed outside a checkout. An editable install uses the checkout's own folders.
The fixture modules are imported under the package's name either way (``encoder_conformance.plugin.fixtures``,
whose ``__path__`` is the fixtures/ folder paths.py finds), never as a top-level ``fixtures`` package.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
FOLDERS = ("suites", "fixtures", "device_profiles")  # the same as encoder_conformance/paths.py BUNDLED_FOLDERS
FILES = ("conftest.py", "pyproject.toml")


class BuildPyWithSuites(build_py):
    """build_py, plus the suites, fixtures and profiles copied into the package's bundled/ folder."""

    def run(self) -> None:
        super().run()
        if self.editable_mode:  # an editable install reads the checkout itself
            return
        target = Path(self.build_lib) / "encoder_conformance" / "bundled"
        shutil.rmtree(target, ignore_errors=True)
        ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
        for folder in FOLDERS:
            shutil.copytree(HERE / folder, target / folder, ignore=ignore)
        for name in FILES:
            shutil.copy2(HERE / name, target / name)


setup(cmdclass={"build_py": BuildPyWithSuites})
