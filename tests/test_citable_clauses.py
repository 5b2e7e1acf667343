"""Every verdict names a source a vendor can look up: a CiA document and section, or the manual's section.

A clause like "reference/conformance-landscape.md §3.1" names a file of this repository, which a vendor
reading a failed report does not have. No text in the suites or their fixtures (docstrings become the
report's test descriptions; spec markers and ``rests_on`` sources become the verdict's basis) may name one.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: what names a file of this repository rather than a published document
REPOSITORY_FILE = re.compile(r"conformance-landscape|python-stack-measured|reference/|seeds/|\b[\w-]+\.(md|txt)\b")


def _texts(path: Path) -> list[tuple[int, str]]:
    """(line, text) of every string literal in a module, docstrings included."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [(node.lineno, node.value) for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str)]


def test_no_verdict_names_a_file_of_this_repository():
    found = [f"{path.relative_to(REPO)}:{line}: {REPOSITORY_FILE.search(text).group(0)}"  # type: ignore[union-attr]
             for folder in ("suites", "fixtures") for path in sorted((REPO / folder).glob("*.py"))
             for line, text in _texts(path) if REPOSITORY_FILE.search(text)]
    assert found == []


def test_the_check_sees_a_repository_file():
    assert REPOSITORY_FILE.search("CiA 305 v3 (reference/conformance-landscape.md §3.1)")
    assert not REPOSITORY_FILE.search("CiA 305 v3.0.0 §8.3.2, WDGA manual §8.2.4")
