"""The library's shape: no import loops, the simulator behind the bus, CiA numbers defined once,
modules of a readable size. These are the rules a newcomer can rely on when finding a concern."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
LIBRARY = REPO / "encoder_conformance"
MAX_LINES = 400


def _module_name(path: Path, root: Path = REPO) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, root: Path = REPO) -> set[str]:
    """Every module ``path`` imports, also inside functions and under TYPE_CHECKING."""
    name = _module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join([*base, node.module] if node.module else base)
            else:
                target = node.module or ""
            found.add(target)
            found.update(f"{target}.{alias.name}" for alias in node.names)
    return found


def _library_graph() -> dict[str, set[str]]:
    modules = {_module_name(p): p for p in LIBRARY.rglob("*.py")}
    return {name: {i for i in _imports(path) if i in modules and i != name} for name, path in modules.items()}


def _loops(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every set of modules that import each other in a loop (Tarjan's strongly connected components)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    loops: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            members = []
            while (member := stack.pop()) != node:
                members.append(member)
            members.append(node)
            if len(members) > 1:
                loops.append(sorted(members))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return sorted(loops)


def test_the_import_reader_sees_every_import(tmp_path):
    """Imports under TYPE_CHECKING, inside functions and relative ones all count."""
    package = tmp_path / "encoder_conformance" / "sim"
    package.mkdir(parents=True)
    module = package / "node.py"
    module.write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from .access import NodeObjectAccess\n"
        "def f():\n    from ..dut import device\n    import encoder_conformance.cia.cia301\n",
        encoding="utf-8",
    )
    found = _imports(module, root=tmp_path)
    assert {"encoder_conformance.sim.access", "encoder_conformance.dut.device",
            "encoder_conformance.cia.cia301"} <= found


def test_the_loop_finder_names_every_loop():
    """Two separate loops are both reported, a chain without a loop is not."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"e"}, "e": {"d"}, "f": {"a"}}
    assert _loops(graph) == [["a", "b", "c"], ["d", "e"]]


def test_no_import_loop_in_the_library():
    """No module imports itself through others, not even under TYPE_CHECKING."""
    assert _loops(_library_graph()) == []


@pytest.mark.parametrize("folder", ["suites", "fixtures"])
def test_only_the_simulator_fixture_imports_the_simulator(folder):
    """Suites and fixtures reach the device through the DUT layer; only fixtures/simulator.py starts a twin."""
    offenders = [
        str(path.relative_to(REPO)) for path in (REPO / folder).rglob("*.py")
        if path.name != "simulator.py" or folder != "fixtures"
        if any(i == "encoder_conformance.sim" or i.startswith("encoder_conformance.sim.") for i in _imports(path))
    ]
    assert offenders == []


#: the library's packages, bottom to top: a package imports from its own folder and lower layers only, never from
#: a neighbour in its own layer (the simulator stands behind the bus: sim/ and dut/ share no code but the layers
#: below them). "(root)" is the package's own top-level modules (errors, exit codes, paths, basis, run summary).
LAYERS: list[set[str]] = [
    {"(root)"},
    {"cia", "config", "vcan"},
    {"profile"},
    {"models", "readings"},
    {"dut", "sim", "history"},
    {"fuzz", "plugin"},
    {"suite_support"},
    {"runs"},
    {"cli"},
]


def _package_of(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and (LIBRARY / parts[1]).is_dir()) else "(root)"


def test_every_package_has_a_layer_and_says_what_it_holds():
    """A new folder is placed in the layer picture, and its __init__ docstring says what it holds."""
    folders = {p.name for p in LIBRARY.iterdir() if (p / "__init__.py").is_file()}
    placed = set().union(*LAYERS)
    assert folders - placed == set()
    undocumented = [f for f in sorted(folders) if not ast.get_docstring(ast.parse(
        (LIBRARY / f / "__init__.py").read_text(encoding="utf-8")))]
    assert undocumented == []


def test_root_holds_only_the_bottom_layer():
    """The package root keeps the modules every layer may use; each concern has a folder."""
    root_modules = sorted(p.stem for p in LIBRARY.glob("*.py"))
    assert root_modules == ["__init__", "__main__", "basis", "errors", "exit_codes", "paths", "run_summary"]


def test_packages_import_only_lower_layers():
    """Imports run downwards: no package reaches up or sideways (e.g. the simulator never imports the DUT
    layer, the plugin or the command line; the run tools never import the command line)."""
    layer_of = {package: n for n, packages in enumerate(LAYERS) for package in packages}
    upward = []
    for name, imports in _library_graph().items():
        if name in ("encoder_conformance", "encoder_conformance.__main__"):  # the entry points sit on top
            continue
        own = _package_of(name)
        for target in imports:
            other = _package_of(target)
            if other != own and layer_of.get(other, -1) >= layer_of[own]:
                upward.append(f"{name} -> {target}")
    assert sorted(upward) == []


def test_no_module_over_400_lines_without_a_reason():
    """A long module says at its top why it is long (the words 'over 400 lines because')."""
    long = []
    for path in LIBRARY.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        if len(text.splitlines()) > MAX_LINES and "over 400 lines because" not in (ast.get_docstring(ast.parse(text))
                                                                                    or ""):
            long.append(f"{path.relative_to(REPO)}: {len(text.splitlines())} lines")
    assert long == []


#: CiA 301 numbers that only encoder_conformance/cia/cia301.py may spell out (signatures, abort codes)
CIA_LITERALS = re.compile(r"0x(65766173|64616F6C|0[5-8]0[0-9A-F]{5})\b", re.IGNORECASE)


def test_cia_numbers_are_defined_once():
    """The 'save'/'load' signatures and SDO abort codes are named in cia/cia301.py and imported elsewhere."""
    spelled = []
    for folder in (LIBRARY, REPO / "suites", REPO / "fixtures"):
        for path in folder.rglob("*.py"):
            if path.relative_to(REPO).as_posix() == "encoder_conformance/cia/cia301.py":
                continue
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                code = line.split("#", 1)[0]
                if CIA_LITERALS.search(code) and '"""' not in code:
                    spelled.append(f"{path.relative_to(REPO)}:{number}: {line.strip()}")
    assert spelled == []
