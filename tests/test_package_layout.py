"""The layout of the whole package is its architecture: the stage table of docs/architecture.md holds.

Imports are read from the source (``ast``), all of them: module level, inside functions, and under
``if TYPE_CHECKING:``. ``from package import module`` is an import of that module; ``from package import
name`` of a name the package's ``__init__`` defines is an import of the package. The repository's
``agents/`` folder is read under its installed name, ``cnc_gym_agents``. (``tests/gcode/test_layout.py``
checks the interpreter's inner layout the same way.)
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
#: Folder → the package name it is imported by.
ROOTS = {REPO / "cnc_gym": "cnc_gym", REPO / "agents": "cnc_gym_agents"}
ARCHITECTURE = REPO / "docs" / "architecture.md"
#: Cycles the layout still has, each a set of modules. Each entry must still be a cycle (so that it is
#: removed with the cycle); none may be added.
KNOWN_CYCLES = [{"cnc_gym.toolpath.segments", "cnc_gym.toolpath.nearest", "cnc_gym.toolpath.records"}]


def _modules() -> dict[str, Path]:
    out = {}
    for root, name in ROOTS.items():
        for path in sorted(root.rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([name, *parts])] = path
    return out


MODULES = _modules()


def _imported_names(name: str, path: Path) -> set[str]:
    """Every module name the source of ``name`` imports (resolved, not filtered)."""
    tree = ast.parse(path.read_text(), str(path))
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{anchor}.{base}" if base else anchor
            for alias in node.names:
                candidate = f"{base}.{alias.name}"
                found.add(candidate if candidate in MODULES else base)
    return found


IMPORTED = {name: _imported_names(name, path) for name, path in MODULES.items()}
GRAPH = {name: {m for m in found if m in MODULES and m != name} for name, found in IMPORTED.items()}


# ------------------------------------------------------------------------------------- the stage table
def _stage_table() -> list[tuple[str, list[str], list[str]]]:
    """(stage, code prefixes, stages it may import) per row of the checked table in docs/architecture.md."""
    text = ARCHITECTURE.read_text()
    marker = "<!-- layout table: checked by tests/test_package_layout.py -->"
    assert marker in text, "docs/architecture.md lost its stage table"
    rows = []
    for line in text.split(marker, 1)[1].strip().splitlines()[2:]:
        if not line.startswith("|"):
            break
        stage, code, allowed = (cell.strip() for cell in line.strip().strip("|").split("|"))
        prefixes = re.findall(r"`(cnc_gym[\w.]*)`", code)
        may = [] if allowed in ("—", "-", "") else [s.strip() for s in allowed.split(",")]
        rows.append((stage, prefixes, may))
    return rows


TABLE = _stage_table()
ORDER = {stage: i for i, (stage, _, _) in enumerate(TABLE)}
ALLOWED = {stage: set(may) | {stage} for stage, _, may in TABLE}


def stage_of(module: str) -> str | None:
    """The stage of the longest code prefix of the table that ``module`` falls under."""
    best, length = None, -1
    for stage, prefixes, _ in TABLE:
        for prefix in prefixes:
            exact = prefix in ("cnc_gym",)  # the package's own __init__, not everything under it
            if (module == prefix or (not exact and module.startswith(prefix + "."))) and len(prefix) > length:
                best, length = stage, len(prefix)
    return best


def _violations(graph: dict[str, set[str]]) -> list[str]:
    out = []
    for name, imports in sorted(graph.items()):
        own = stage_of(name)
        for target in sorted(imports):
            if stage_of(target) not in ALLOWED[own]:
                out.append(f"{name} ({own}) imports {target} ({stage_of(target)})")
    return out


def test_the_table_is_ordered_and_names_known_stages():
    assert [stage for stage, _, _ in TABLE][:3] == ["shared", "toolpath", "gcode"]
    for stage, prefixes, may in TABLE:
        assert prefixes, f"{stage}: no code named"
        for other in may:
            assert other in ORDER, f"{stage} may import an unknown stage {other!r}"
            assert ORDER[other] < ORDER[stage], f"{stage} may import {other}, which is not an earlier stage"


def test_every_module_belongs_to_one_stage():
    unplaced = sorted(name for name in MODULES if stage_of(name) is None)
    assert not unplaced, f"modules in no stage of docs/architecture.md: {unplaced}"


def test_no_stage_imports_a_stage_it_may_not():
    problems = _violations(GRAPH)
    assert not problems, "\n".join(problems)


def test_cnc_gym_never_imports_the_learning_code():
    for name, found in IMPORTED.items():
        if name.startswith("cnc_gym."):
            bad = sorted(m for m in found if m.split(".")[0] in ("agents", "cnc_gym_agents"))
            assert not bad, f"{name} imports {bad}"


def test_nothing_imports_the_learning_code_by_its_folder_name():
    # Scripts, tests and the code itself use the installed name (cnc_gym_agents); "agents" would be
    # another copy of the modules, and a generic name in site-packages.
    for folder in ("cnc_gym", "agents", "scripts", "tests", "examples"):
        for path in sorted((REPO / folder).rglob("*.py")):
            tree = ast.parse(path.read_text(), str(path))
            for node in ast.walk(tree):
                if isinstance(node, ast.Import):
                    names = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and not node.level:
                    names = [node.module or ""]
                else:
                    continue
                assert not any(n == "agents" or n.startswith("agents.") for n in names), (
                    f"{path.relative_to(REPO)}:{node.lineno} imports agents; use cnc_gym_agents")


# ------------------------------------------------------------------------------------------------ cycles
def _cycles(graph: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph.get(node, ())):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = set()
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.add(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(component)

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def unit_of(module: str) -> str:
    """The package a module belongs to (a package is its own unit; so is a module at the top of a root)."""
    if MODULES[module].name == "__init__.py" or module.count(".") == 1:
        return module
    return module.rsplit(".", 1)[0]


def _package_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for name, imports in graph.items():
        unit = unit_of(name)
        out.setdefault(unit, set()).update(unit_of(m) for m in imports if unit_of(m) != unit)
    return out


def test_no_import_cycles_between_modules_type_checking_imports_included():
    cycles = _cycles(GRAPH)
    new = [sorted(c) for c in cycles if c not in KNOWN_CYCLES]
    assert not new, f"import cycles: {new}"
    gone = [sorted(c) for c in KNOWN_CYCLES if c not in cycles]
    assert not gone, f"these cycles are gone: remove them from KNOWN_CYCLES: {gone}"


def test_no_import_cycles_between_packages():
    cycles = _cycles(_package_graph(GRAPH))
    assert not cycles, f"import cycles between packages: {[sorted(c) for c in cycles]}"


# ------------------------------------------------------------------------------------ the checks can fail
@pytest.mark.parametrize(("source", "target"), [
    ("cnc_gym.motion.controller", "cnc_gym.envs.feedrate"),     # a stage importing a later one
    ("cnc_gym.envs.planner_prior", "cnc_gym.policies.classical"),  # the env importing a policy
    ("cnc_gym.rollout", "cnc_gym.runner"),
])  # fmt: skip
def test_the_stage_check_finds_a_planted_import(source, target):
    graph = {k: set(v) for k, v in GRAPH.items()}
    graph[source].add(target)
    assert _violations(graph)


def test_the_cycle_checks_find_planted_cycles():
    graph = {k: set(v) for k, v in GRAPH.items()}
    graph["cnc_gym.errors"].add("cnc_gym.config")  # config imports errors: a two-module cycle
    assert any(c == {"cnc_gym.errors", "cnc_gym.config"} for c in _cycles(graph))
    graph = {k: set(v) for k, v in GRAPH.items()}
    graph["cnc_gym.benchmark.suites"].add("cnc_gym.runner")
    graph["cnc_gym.runner"].add("cnc_gym.benchmark.metrics")
    assert _cycles(_package_graph(graph))
