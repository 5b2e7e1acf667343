"""The library's shape: no import loops, the simulator behind the bus, CiA numbers defined once,
modules of a readable size. These are the rules a newcomer can rely on when finding a concern."""

from __future__ import annotations

import ast
import builtins
import importlib
import importlib.util
import inspect
import io
import re
import tokenize
from pathlib import Path
from types import ModuleType

REPO = Path(__file__).resolve().parents[1]
LIBRARY = REPO / "encoder_conformance"
MAX_LINES = 400


def _module_name(path: Path, root: Path = REPO) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, root: Path = REPO, at_import: bool = False) -> set[str]:
    """Every module ``path`` imports, also inside functions and under TYPE_CHECKING; ``at_import``: only those
    importing ``path`` imports (not inside a function, not under TYPE_CHECKING)."""
    name = _module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in (_nodes_run_at_import(tree) if at_import else ast.walk(tree)):
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


def _nodes_run_at_import(node: ast.AST) -> list[ast.AST]:
    """The nodes executed when the module is imported: not a function's body, not an ``if TYPE_CHECKING:`` block."""
    found: list[ast.AST] = []
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
            continue
        if isinstance(child, ast.If) and ast.unparse(child.test) in ("TYPE_CHECKING", "typing.TYPE_CHECKING"):
            found += _nodes_run_at_import(ast.Module(body=child.orelse, type_ignores=[]))
            continue
        found += [child, *_nodes_run_at_import(child)]
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


def test_the_import_reader_tells_what_runs_at_import(tmp_path):
    """``at_import``: a module-level import counts, one in a function or under TYPE_CHECKING does not."""
    module = tmp_path / "m.py"
    module.write_text("import a\nfrom typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import b\n"
                      "else:\n    import c\ndef f():\n    import d\nclass K:\n    import e\n", encoding="utf-8")
    assert _imports(module, root=tmp_path, at_import=True) == {"a", "typing", "typing.TYPE_CHECKING", "c", "e"}


#: the simulator's two faces (DESIGN.md §2): its top level is the tester-side API, the only part of sim/ imported
#: outside it; sim/engine/ is what the twin's process runs. The project's own tests (tests/) may import the engine too,
#: to test its parts; suites/ and fixtures/ import nothing of sim/ (the run's twin is started by
#: plugin/twin_launch.py).
SIM = "encoder_conformance.sim"
SIM_API = {"control", "fault_catalogue", "forked", "hold_faults", "process", "twin"}
#: where a twin is started (sim.process's launch_simulator / start_simulator, sim.twin's start_in_process) outside sim/
TWIN_STARTED_IN = {
    "encoder_conformance/plugin/twin_launch.py": "the run's twin: the one place its log and memory files are made",
    "encoder_conformance/runs/false_pass_matrix.py": "a twin as a bench device, on a bus of its own",
}
_STARTS_A_TWIN = re.compile(r"\b(launch_simulator|start_simulator|start_in_process)\(")


def _outside_sim() -> list[Path]:
    """Every Python file of the project outside sim/ but tests/: the library's other packages, suites/, fixtures/
    and the top-level modules (conftest.py, setup.py)."""
    library = [p for p in LIBRARY.rglob("*.py") if not p.relative_to(LIBRARY).as_posix().startswith("sim/")]
    return sorted([*library, *(REPO / "suites").rglob("*.py"), *(REPO / "fixtures").rglob("*.py"), *REPO.glob("*.py")])


def test_the_simulator_has_two_faces():
    """sim/'s top level holds the tester-side API and nothing else; every other module is in sim/engine/."""
    folder = LIBRARY / "sim"
    assert {p.stem for p in folder.glob("*.py")} - {"__init__"} == SIM_API
    assert {p.name for p in folder.iterdir() if p.is_dir() and p.name != "__pycache__"} == {"engine"}


def test_outside_sim_only_the_tester_side_api_is_imported():
    """No module outside sim/ (tests/ aside) imports or names the engine, and suites/ and fixtures/ import nothing
    of sim/: they reach the twin through the DUT layer and the ``simulator`` fixture (plugin/twin_launch.py)."""
    offenders = []
    for path in _outside_sim():
        where = path.relative_to(REPO).as_posix()
        for target in sorted(_imports(path)):
            parts = target.split(".")
            if parts[:2] != SIM.split("."):
                continue
            if where.startswith(("suites/", "fixtures/")) or (len(parts) > 2 and parts[2] not in SIM_API):
                offenders.append(f"{where} -> {target}")
        if f"{SIM}.engine" in path.read_text(encoding="utf-8"):
            offenders.append(f"{where} names {SIM}.engine")
    assert offenders == []


def test_the_tester_side_api_loads_no_engine():
    """The API imports the engine only inside its functions (or for type checking): the plugin, the command line and
    a bench's power command import it without the twin."""
    loading = [f"{path.relative_to(REPO)} -> {target}" for path in (LIBRARY / "sim").glob("*.py")
               for target in sorted(_imports(path, at_import=True)) if target.startswith(f"{SIM}.engine")]
    assert loading == []


def test_the_twin_is_started_in_one_place():
    """Outside sim/ a twin is started only where TWIN_STARTED_IN says why (a run's twin by plugin/twin_launch.py)."""
    found = [f"{path.relative_to(REPO)}:{n}" for path in _outside_sim()
             if path.relative_to(REPO).as_posix() not in TWIN_STARTED_IN
             for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if _STARTS_A_TWIN.search(line)]
    assert found == []


def test_the_design_draws_the_simulator_faces():
    """DESIGN.md §2 names the tester-side API module by module, and the engine's folder."""
    design = (LIBRARY / "DESIGN.md").read_text(encoding="utf-8")
    layers = design[design.index("## 2."):design.index("## 3.")]
    assert [m for m in sorted(SIM_API) if f"sim/{m}.py" not in layers] == []
    assert "sim/engine/" in layers


#: the library's packages, bottom to top: a package imports from its own folder and lower layers only, never from
#: a neighbour in its own layer (the simulator stands behind the bus: sim/ and dut/ share no code but the layers
#: below them). "(root)" is the package's own top-level modules (errors, exit codes, paths, basis, run summary,
#: deadline).
LAYERS: list[set[str]] = [
    {"(root)"},
    {"cia", "config", "vcan"},
    {"profile"},
    {"models", "open_points"},
    {"dut", "sim", "history"},
    {"fuzz", "plugin", "probe"},
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
    assert root_modules == ["__init__", "__main__", "basis", "coverage", "deadline", "errors", "exit_codes", "paths",
                            "run_summary"]


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


#: COB-ID function code bases (CiA 301 §7.3.5: TPDO1-4, SDO response/request, NMT error control) and the LSS
#: COB-IDs (CiA 305): written as a hex literal only in encoder_conformance/cia/, imported everywhere else
COB_ID_LITERALS = {0x180, 0x280, 0x380, 0x480, 0x580, 0x600, 0x700, 0x7E4, 0x7E5}
#: the folders the COB-ID literal rule covers
COB_ID_FOLDERS = [LIBRARY, REPO / "suites", REPO / "fixtures"]
#: a constant named as a CiA number (an abort byte, a COB-ID or its base) is defined in cia/ only
CIA_CONSTANT_NAME = re.compile(r"^_?[A-Z0-9_]*(ABORT|_BASE|COB_ID)[A-Z0-9_]*$")


def _outside_cia(folders: list[Path]) -> list[Path]:
    return [path for folder in folders for path in sorted(folder.rglob("*.py"))
            if not path.relative_to(REPO).as_posix().startswith("encoder_conformance/cia/")]


def _hex_literals(path: Path) -> list[tuple[int, str]]:
    """(line, literal) of every hexadecimal number in the code (not in strings or comments)."""
    tokens = tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline)
    return [(t.start[0], t.string) for t in tokens
            if t.type == tokenize.NUMBER and t.string.lower().startswith("0x")]


def test_the_literal_finder_sees_code_only(tmp_path):
    """A literal in code counts; the same digits in a string, a docstring or a comment do not."""
    module = tmp_path / "m.py"
    module.write_text('"""0x580 in a docstring"""\nA = 0x580 + 1  # 0x700\nB = "0x600"\nC = 0X7e5\n', encoding="utf-8")
    assert _hex_literals(module) == [(2, "0x580"), (4, "0X7e5")]


def test_cob_id_bases_are_not_spelled_outside_cia():
    """580h, 600h, 700h, 180h-480h, 7E4h/7E5h are named in cia/cia301.py and cia/cia305.py (SDO_RESPONSE_BASE,
    SDO_REQUEST_BASE, HEARTBEAT_BASE, TPDO_BASES, the LSS COB-IDs) and imported where a COB-ID is meant."""
    spelled = [f"{path.relative_to(REPO)}:{line}: {literal}" for path in _outside_cia(COB_ID_FOLDERS)
               for line, literal in _hex_literals(path) if int(literal, 16) in COB_ID_LITERALS]
    assert spelled == []


def test_cia_constants_and_the_nmt_table_are_defined_once():
    """No module outside cia/ gives a CiA number a name of its own (``ABORT = 0x80``, ``EMCY_BASE = 0x80``) or
    writes out where the NMT commands lead (cia301.NMT_COMMAND_TARGET)."""
    found = []
    for path in _outside_cia([LIBRARY, REPO / "suites", REPO / "fixtures"]):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Assign | ast.AnnAssign) and isinstance(node.value, ast.Constant) \
                    and isinstance(node.value.value, int) and not isinstance(node.value.value, bool):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                found += [f"{path.relative_to(REPO)}:{node.lineno}: {t.id}" for t in targets
                          if isinstance(t, ast.Name) and CIA_CONSTANT_NAME.match(t.id)]
            if isinstance(node, ast.Dict) and node.keys and all(
                    isinstance(k, ast.Attribute) and isinstance(k.value, ast.Name) and k.value.id == "NmtCommand"
                    and isinstance(v, ast.Attribute) and isinstance(v.value, ast.Name) and v.value.id == "NmtState"
                    for k, v in zip(node.keys, node.values, strict=True)):
                found.append(f"{path.relative_to(REPO)}:{node.lineno}: an NmtCommand -> NmtState table")
    assert found == []


def _library_modules() -> dict[str, ModuleType]:
    """Every module of the library, imported (not the ``__main__`` entry points, which run a command)."""
    names = sorted(_module_name(p) for p in LIBRARY.rglob("*.py") if p.stem != "__main__")
    return {name: importlib.import_module(name) for name in names}


def _exception_classes() -> dict[str, type[BaseException]]:
    """Every exception class the library defines, by qualified name; classes defined inside functions (which
    inspection of a module does not reach) are found with ast and judged by their bases."""
    found: dict[str, type[BaseException]] = {}
    for name, module in _library_modules().items():
        path = Path(module.__file__ or "")
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ClassDef):
                continue
            cls = getattr(module, node.name, None)
            if not (inspect.isclass(cls) and cls.__module__ == name and cls.__qualname__ == node.name):
                # nested (in a function): stand in with a class built from its bases as the module names them
                bases = tuple(b for b in (_resolve(module, base) for base in node.bases) if inspect.isclass(b))
                cls = type(node.name, bases, {}) if bases else None
            if inspect.isclass(cls) and issubclass(cls, BaseException):
                found[f"{name}.{node.name}"] = cls
    return found


def _resolve(module: ModuleType, expression: ast.expr) -> object:
    if isinstance(expression, ast.Name):
        return vars(module).get(expression.id, getattr(builtins, expression.id, None))
    if isinstance(expression, ast.Attribute):
        owner = _resolve(module, expression.value)
        return getattr(owner, expression.attr, None)
    return None


def test_every_exception_class_is_in_the_one_tree():
    """Every exception class of the library derives from errors.EncoderConformanceError (RunInterrupted, by design
    a KeyboardInterrupt, and TypedSkip, by design pytest's skip, aside: ``except Exception`` must not catch them)
    and is defined in errors.py, unless it also needs a base of another library (dut/link/device.py's SdoAborted, also
    canopen's SdoAbortedError)."""
    from encoder_conformance.errors import EncoderConformanceError, RunInterrupted
    from encoder_conformance.plugin.skips import TypedSkip

    classes = _exception_classes()
    assert "encoder_conformance.errors.UsageError" in classes  # the finder works
    outside = [name for name, cls in classes.items()
               if cls not in (RunInterrupted, TypedSkip) and not issubclass(cls, EncoderConformanceError)]
    assert outside == []
    elsewhere = [name for name, cls in classes.items() if not name.startswith("encoder_conformance.errors.")
                 and not any(b.__module__.partition(".")[0] not in ("encoder_conformance", "builtins")
                             for b in cls.__mro__)]
    assert elsewhere == []


def test_the_error_picture_names_every_class():
    """errors.py's docstring draws the tree: it names every exception class of the library, and no other."""
    from encoder_conformance import errors

    drawn = set(re.findall(r"\+-- (\w+)", errors.__doc__ or ""))
    defined = {name.rpartition(".")[2] for name in _exception_classes()}
    assert defined - drawn == set()
    assert {name for name in drawn - defined if not hasattr(builtins, name)} == set()


#: the suites' helpers that need pytest or the evidence (formerly suite_support/): a face, as dut's packages have
SUITE_HELPERS = LIBRARY / "plugin" / "suite_helpers"
#: the packages a suite imports through their faces only
FACED = ("encoder_conformance.dut", "encoder_conformance.plugin.suite_helpers")


def test_hooks_live_in_the_plugin_and_fixture_modules_hold_fixtures():
    """No pytest hook in conftest.py, fixtures/ or suites/ (the plugin's hooks.py is the hub); a fixture module
    defines fixtures and private helpers only (device-handling classes live in dut/ or plugin/suite_helpers/)."""
    misplaced = []
    for path in [REPO / "conftest.py", *(REPO / "fixtures").glob("*.py"), *(REPO / "suites").glob("*.py")]:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            name = getattr(node, "name", "")
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and name.startswith("pytest_"):
                misplaced.append(f"{path.relative_to(REPO)}: hook {name}")
            if path.parent.name != "fixtures" or name.startswith("_"):
                continue
            fixture = isinstance(node, ast.FunctionDef) and any(
                "fixture" in ast.unparse(decorator) for decorator in node.decorator_list)
            if isinstance(node, ast.ClassDef | ast.FunctionDef) and not fixture:
                misplaced.append(f"{path.relative_to(REPO)}: {name} is not a fixture")
    assert misplaced == []


def test_suites_and_fixtures_do_not_import_fixture_modules():
    """Suites get their helpers from the package (dut/, plugin/suite_helpers/), which works wherever it is installed."""
    offenders = [str(path.relative_to(REPO)) for folder in ("suites", "fixtures")
                 for path in (REPO / folder).glob("*.py")
                 if any(i == "fixtures" or i.startswith(("fixtures.", "encoder_conformance.plugin.fixtures"))
                        for i in _imports(path))]
    assert offenders == []


def test_suites_skip_only_with_a_typed_reason():
    """A test ends without a verdict only through plugin/skips.py (a scope kind or a coverage.Hold): a bare
    ``pytest.skip`` in the suites, fixtures or the suites' helpers would be an untyped reason."""
    bare = []
    for folder in (REPO / "suites", REPO / "fixtures", SUITE_HELPERS, LIBRARY / "dut"):
        for path in folder.rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Call) and ast.unparse(node.func) in ("pytest.skip", "skip"):
                    bare.append(f"{path.relative_to(REPO)}:{node.lineno}")
    assert bare == []


#: where an NMT state command (start, stop, enter pre-operational) may be sent other than through dut/nmt/nmt_states.py
#: (``dut.nmt.transition``): places that judge the command itself or time from it, and custody, which may always talk
#: (issue 39: one way into a state, seen by what the state answers)
NMT_STATE_COMMANDS_ALSO_IN = {
    "encoder_conformance/dut/nmt/heartbeat_state.py": "leaves stopped before an SDO request, seeing 7Fh",
    "encoder_conformance/dut/lss/lss_device.py": "the LSS states of a device whose manual allows LSS only in some",
    "encoder_conformance/dut/lss/lss_custody.py": "the LSS put-back",
    "encoder_conformance/dut/custody/custody.py": "the snapshot and the give-back",
    "encoder_conformance/dut/tpdo/periodic_capture.py": "times the event-timer stream from the start",
    "suites/test_pdo_timing.py": "times the TPDOs from the start",
    "suites/test_nmt_state_machine.py": "the model's own steps, each confirmed against the model",
}
_STATE_COMMAND = re.compile(
    r"""(\.nmt\.command|\bsend_command|\bsend_in_custody)\((\s*[\w.]+,)?\s*["'](start|stop|pre-operational)["']""")
NMT_HOME = "encoder_conformance/dut/nmt/nmt_states.py"


def test_nmt_states_are_entered_in_one_place():
    """Suites, fixtures and the DUT layer enter an NMT state through ``dut.nmt.transition`` (dut/nmt/nmt_states.py),
    which sees it there."""
    found = []
    for folder in (REPO / "suites", REPO / "fixtures", LIBRARY / "dut", SUITE_HELPERS):
        for path in folder.rglob("*.py"):
            where = path.relative_to(REPO).as_posix()
            if where != NMT_HOME and where not in NMT_STATE_COMMANDS_ALSO_IN:
                found += [f"{where}:{n}" for n, line in enumerate(path.read_text().splitlines(), 1)
                          if _STATE_COMMAND.search(line)]
    assert found == [], "NMT state commands outside dut/nmt/nmt_states.py (use dut.nmt.transition)"


def test_the_state_command_finder_sees_every_spelling():
    """The face's command, the DUT layer's own sender and custody's are all seen; other commands are not."""
    lines = ['dut.nmt.command("start")', 'send_command(self.dut, "pre-operational", node_id=3)',
             "send_in_custody(dut, 'stop', 5)", 'dut.nmt.command("reset-node")', 'dut.nmt.transition("stopped", j, n)',
             'nmt.command("start", node_id=0)']  # the last: the NMT suite's observer, judging the command itself
    assert [bool(_STATE_COMMAND.search(line)) for line in lines] == [True, True, True, False, False, False]


#: suite tests that switch the LSS state themselves rather than by ``LssDevice.transition`` (dut/lss/lss_device.py):
#: each judges the switch itself (issue 41: one way into a state, seen by what the state answers)
LSS_SWITCH_JUDGED_IN = {
    "test_switch_global_enters_and_leaves_configuration": "judges switch state global, into and out of configuration",
    "test_switch_selective_only_own_address": "judges switch state selective's 44h answer",
    "test_lss_in_nmt_state": "judges whether LSS is obeyed in an NMT state: no answer may be the verdict",
}
_LSS_SWITCH = {"select", "leave", "switch_global", "switch_selective"}


def test_lss_states_are_entered_in_one_place():
    """Suites and fixtures enter the LSS configuration or waiting state through ``lss.transition`` (which sees the
    selection answered where the device has switch state selective), but in the tests that judge the switch."""
    found = []
    for path in sorted([*(REPO / "suites").glob("*.py"), *(REPO / "fixtures").glob("*.py")]):
        for function in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(function, ast.FunctionDef) or function.name in LSS_SWITCH_JUDGED_IN:
                continue
            found += [f"{path.relative_to(REPO)}:{call.lineno} {function.name}" for call in ast.walk(function)
                      if isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute)
                      and call.func.attr in _LSS_SWITCH]
    assert found == [], "LSS state switched outside LssDevice.transition (use lss.transition)"


#: modules outside dut/nmt/ that may build an NMT command frame themselves: the twin decodes them (sim/), cia/ names
#: them; every other NMT command the tester sends goes through dut.nmt (issue 41)
NMT_FRAMES_ALSO_IN: dict[str, str] = {}
NMT_FRAMES_HOMES = ("encoder_conformance/dut/nmt/", "encoder_conformance/sim/", "encoder_conformance/cia/")
_NMT_FRAME = re.compile(r"\b(NMT_COB_ID|NMT_COMMAND_NAMES)\b|\.nmt\(")


def test_nmt_commands_are_sent_only_through_dut_nmt():
    """No module builds an NMT command frame (COB-ID 000h, the command table) or calls a device's old ``nmt()``
    outside dut/nmt/: tests of NMT commands call ``dut.nmt.command``, custody and the LSS steps dut/nmt/commands.py."""
    found = []
    for folder in (REPO / "suites", REPO / "fixtures", LIBRARY):
        for path in folder.rglob("*.py"):
            where = path.relative_to(REPO).as_posix()
            if not where.startswith(NMT_FRAMES_HOMES) and where not in NMT_FRAMES_ALSO_IN:
                found += [f"{where}:{n}" for n, line in enumerate(path.read_text().splitlines(), 1)
                          if _NMT_FRAME.search(line.split("#")[0])]
    assert found == [], "NMT commands outside dut/nmt/ (use dut.nmt.command or dut/nmt/commands.py)"


def _faces() -> dict[str, set[str]]:
    """Each package of dut/ (and dut itself, and plugin/suite_helpers/), and the names its face exports: its
    ``__init__``'s names, and its modules."""
    from encoder_conformance.dut.face_exports import face_names

    packages = [LIBRARY / "dut", SUITE_HELPERS,
                *(p.parent for p in (LIBRARY / "dut").glob("*/__init__.py"))]
    return {_module_name(p): set(face_names(str(p / "__init__.py"))) | {m.stem for m in p.glob("*.py")}
            for p in packages}


def test_suites_import_only_the_faces_of_dut():
    """A suite imports from ``encoder_conformance.dut`` or one of its packages (``dut.nmt``, ``dut.tpdo``, ...), and
    from ``plugin.suite_helpers`` (the helpers that need pytest or the evidence), the names its face exports, never a
    module inside a package: what a test uses has one address per protocol."""
    faces = _faces()
    found = []
    for path in (REPO / "suites").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                found += [f"{path.name}: import {a.name}" for a in node.names if a.name.startswith(FACED)]
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith(FACED):
                module = node.module or ""
                if module not in faces:
                    found.append(f"{path.name}: from {module}")
                else:
                    found += [f"{path.name}: {module}.{a.name}" for a in node.names if a.name not in faces[module]]
    assert found == [], "suites import dut's faces only (add the name to the package's __init__)"


def test_every_face_name_resolves():
    """Each name a face of dut/ exports is there on first use (``dut/face_exports.py`` imports it lazily)."""
    missing = []
    for package, names in _faces().items():
        module = importlib.import_module(package)
        missing += [f"{package}.{name}" for name in sorted(names) if not hasattr(module, name)
                    and importlib.util.find_spec(f"{package}.{name}") is None]
    assert missing == []
