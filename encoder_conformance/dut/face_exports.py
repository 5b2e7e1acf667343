"""A package's face: the names its ``__init__`` exports, each imported from its module on first use.

A face ``__init__`` imports what it offers under ``if TYPE_CHECKING:`` (so mypy and readers see every name and
where it is defined) and sets ``__getattr__ = lazy_face(__name__, __file__)``: the first ``from
encoder_conformance.dut.nmt import reach`` imports ``nmt_states`` then (PEP 562). Importing a face eagerly would
run every module of the package whenever any one of them is imported, and the protocols use each other's modules
(custody the bench's, the TPDOs the NMT states'), so an eager face would meet a half-imported module.
"""

from __future__ import annotations

import ast
import importlib
from collections.abc import Callable
from pathlib import Path


def face_names(init_file: str) -> dict[str, tuple[str, str]]:
    """Each name the ``if TYPE_CHECKING:`` block of ``init_file`` imports: the module it comes from and its name
    there."""
    names: dict[str, tuple[str, str]] = {}
    for node in ast.parse(Path(init_file).read_text(encoding="utf-8")).body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for statement in node.body:
                if isinstance(statement, ast.ImportFrom) and statement.module:
                    module = statement.module
                    names.update({alias.asname or alias.name: (module, alias.name) for alias in statement.names})
    return names


def lazy_face(package: str, init_file: str) -> Callable[[str], object]:
    """The module ``__getattr__`` of the face ``package`` (its ``__init__`` is ``init_file``)."""
    names: dict[str, tuple[str, str]] = {}

    def __getattr__(name: str) -> object:
        if not names:
            names.update(face_names(init_file))
        if name not in names:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module, original = names[name]
        return getattr(importlib.import_module(module), original)

    return __getattr__
