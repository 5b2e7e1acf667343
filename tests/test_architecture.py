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


def _module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """Every module ``path`` imports, also inside functions and under TYPE_CHECKING."""
    package = _module_name(path) if path.name == "__init__.py" else _module_name(path).rpartition(".")[0]
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


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt):], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_no_import_loop_in_the_library():
    """No module imports itself through others, not even under TYPE_CHECKING."""
    assert _cycle(_library_graph()) is None


@pytest.mark.parametrize("folder", ["suites", "fixtures"])
def test_only_the_simulator_fixture_imports_the_simulator(folder):
    """Suites and fixtures reach the device through the DUT layer; only fixtures/simulator.py starts a twin."""
    offenders = [
        str(path.relative_to(REPO)) for path in (REPO / folder).glob("*.py")
        if path.name != "simulator.py" or folder != "fixtures"
        if any(i == "encoder_conformance.sim" or i.startswith("encoder_conformance.sim.") for i in _imports(path))
    ]
    assert offenders == []


def test_simulator_imports_nothing_of_the_tester_side():
    """sim/ stands behind the bus: it may use the profile and the CiA vocabulary, not the DUT layer,
    the plugin, the command line or the suites' helpers."""
    tester_side = ("dut", "plugin", "cli", "fault_matrix", "checks", "parameters", "sim_process", "restore_command")
    offenders = {
        name: sorted(i for i in imports if i.split(".")[1] in tester_side)
        for name, imports in _library_graph().items()
        if name.startswith("encoder_conformance.sim.")
    }
    assert {k: v for k, v in offenders.items() if v} == {}


def test_no_module_over_400_lines_without_a_reason():
    """A long module says at its top why it is long (the words 'over 400 lines because')."""
    long = []
    for path in LIBRARY.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        if len(text.splitlines()) > MAX_LINES and "over 400 lines because" not in (ast.get_docstring(ast.parse(text))
                                                                                    or ""):
            long.append(f"{path.relative_to(REPO)}: {len(text.splitlines())} lines")
    assert long == []


#: CiA 301 numbers that only encoder_conformance/cia301.py may spell out (signatures, abort codes)
CIA_LITERALS = re.compile(r"0x(65766173|64616F6C|0[5-8]0[0-9A-F]{5})\b", re.IGNORECASE)


def test_cia_numbers_are_defined_once():
    """The 'save'/'load' signatures and SDO abort codes are named in cia301.py and imported elsewhere."""
    spelled = []
    for folder in (LIBRARY, REPO / "suites", REPO / "fixtures"):
        for path in folder.rglob("*.py"):
            if path.name == "cia301.py":
                continue
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                code = line.split("#", 1)[0]
                if CIA_LITERALS.search(code) and '"""' not in code:
                    spelled.append(f"{path.relative_to(REPO)}:{number}: {line.strip()}")
    assert spelled == []
