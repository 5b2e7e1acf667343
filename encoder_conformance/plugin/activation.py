"""Whether a pytest session is about the suites, and the plugin's modules loaded only when it is.

The package's ``pytest11`` entry point (plugin/hooks.py) is imported by every pytest session where the package
is installed, another project's too. There it adds its (prefixed) options and does nothing else: no hook acts,
and none of the modules behind the hooks is imported (the device, the twin, the profiles: about a second of
imports). This module and what hooks.py imports at its top stay light for that (tests/test_option_prefix.py).
"""

from __future__ import annotations

import importlib
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from encoder_conformance.paths import CONTENT_ROOT, SUITES_DIR

if TYPE_CHECKING:
    import pytest


def runs_suites(config: pytest.Config) -> bool:
    """True when this pytest run includes the conformance suites (not only the self-tests)."""
    suites = SUITES_DIR
    paths = [Path(a.split("::")[0]).resolve() for a in config.args] or [suites]
    return any(p == suites or suites in p.parents for p in paths)


def is_ours(config: pytest.Config) -> bool:
    """The suites' own session, or the self-tests of the checkout they live in."""
    return runs_suites(config) or config.rootpath.resolve() == CONTENT_ROOT


class LazyModule:
    """A module imported at the first use of one of its attributes (the hooks use theirs only in a session of
    ours). Kept once imported: ``importlib.import_module`` on every attribute cost ~0.1 s of a full run's hooks.
    Given the namespace that holds it (``globals()``) and its name there, it puts the module itself in its place
    once imported: the hooks then reach the module directly (this object's ``__getattr__`` on each of the ~5,600
    uses in an acceptance's hooks cost ~20 ms)."""

    def __init__(self, name: str, namespace: dict[str, Any] | None = None, alias: str | None = None) -> None:
        self._name = name
        self._loaded: ModuleType | None = None
        self._namespace = namespace
        self._alias = alias

    def _module(self) -> ModuleType:
        if self._loaded is None:
            self._loaded = importlib.import_module(self._name)
            if self._namespace is not None and self._alias is not None:
                self._namespace[self._alias] = self._loaded
        return self._loaded

    def __getattr__(self, attribute: str) -> Any:
        if attribute.startswith("_"):  # pytest looks for fixture markers on every name of a plugin: not ours
            raise AttributeError(attribute)
        return getattr(self._module(), attribute)
