"""The layout of the whole package is its architecture: the stage table of docs/architecture.md holds.

Imports are read from the source, all of them (``tests/import_graph.py``); the repository's ``agents/``
folder is read under its installed name, ``cnc_gym_agents``. (``tests/gcode/test_layout.py`` checks the
interpreter's inner layout from the same graph.)
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest
from import_graph import cycles, graph, imported_names, modules

REPO = Path(__file__).resolve().parents[1]
#: Folder → the package name it is imported by.
ROOTS = {REPO / "cnc_gym": "cnc_gym", REPO / "agents": "cnc_gym_agents"}
ARCHITECTURE = REPO / "docs" / "architecture.md"
#: Cycles the layout still has, each a set of modules. Each entry must still be a cycle (so that it is
#: removed with the cycle); none may be added. None is left.
KNOWN_CYCLES: list[set[str]] = []


MODULES = modules(ROOTS)
IMPORTED = {name: imported_names(name, path, MODULES) for name, path in MODULES.items()}
GRAPH = graph(MODULES)


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


def _violations(edges: dict[str, set[str]]) -> list[str]:
    out = []
    for name, imports in sorted(edges.items()):
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
def unit_of(module: str) -> str:
    """The package a module belongs to; a package is its own unit, and so is a module at the top of
    ``cnc_gym`` (each of those is a stage or a shared module of its own)."""
    if MODULES[module].name == "__init__.py" or (module.startswith("cnc_gym.") and module.count(".") == 1):
        return module
    return module.rsplit(".", 1)[0]


def _package_graph(edges: dict[str, set[str]]) -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for name, imports in edges.items():
        unit = unit_of(name)
        out.setdefault(unit, set()).update(unit_of(m) for m in imports if unit_of(m) != unit)
    return out


def test_no_import_cycles_between_modules_type_checking_imports_included():
    found = cycles(GRAPH)
    new = [sorted(c) for c in found if c not in KNOWN_CYCLES]
    assert not new, f"import cycles: {new}"
    gone = [sorted(c) for c in KNOWN_CYCLES if c not in found]
    assert not gone, f"these cycles are gone: remove them from KNOWN_CYCLES: {gone}"


def test_no_import_cycles_between_packages():
    found = cycles(_package_graph(GRAPH))
    assert not found, f"import cycles between packages: {[sorted(c) for c in found]}"


# ----------------------------------------------------------------------------------- the env's engine
ENGINE = "cnc_gym.envs.engine"
#: The engine's modules in their import order: each imports only those before it (docs/architecture.md).
ENGINE_ORDER = ["layout", "specs", "bank", "step", "episode", "batch"]


def _engine_violations(edges: dict[str, set[str]]) -> list[str]:
    out = []
    for i, module in enumerate(ENGINE_ORDER):
        for target in sorted(edges[f"{ENGINE}.{module}"]):
            inside = target == ENGINE or target.startswith(ENGINE + ".")
            if inside and target.removeprefix(ENGINE + ".") not in ENGINE_ORDER[:i]:
                out.append(f"{ENGINE}.{module} imports {target}")
    return out


def test_the_engine_modules_import_in_one_direction():
    engine = {ENGINE} | {f"{ENGINE}.{module}" for module in ENGINE_ORDER}
    assert {name for name in MODULES if name.startswith(ENGINE)} == engine, "a module not in ENGINE_ORDER"
    problems = _engine_violations(GRAPH)
    assert not problems, "\n".join(problems)


# ------------------------------------------------------------------------------------ the checks can fail
@pytest.mark.parametrize(("source", "target"), [
    ("cnc_gym.motion.controller", "cnc_gym.envs.feedrate"),     # a stage importing a later one
    ("cnc_gym.envs.planner_prior", "cnc_gym.policies.classical"),  # the env importing a policy
    ("cnc_gym.rollout", "cnc_gym.runner"),
])  # fmt: skip
def test_the_stage_check_finds_a_planted_import(source, target):
    edges = {k: set(v) for k, v in GRAPH.items()}
    edges[source].add(target)
    assert _violations(edges)


def test_the_engine_check_finds_a_planted_import():
    for source, target in (("layout", "step"), ("bank", "batch"), ("specs", "")):
        edges = {k: set(v) for k, v in GRAPH.items()}
        edges[f"{ENGINE}.{source}"].add(f"{ENGINE}.{target}".rstrip("."))  # "": the package's __init__
        assert _engine_violations(edges), (source, target)


def test_the_cycle_checks_find_plantedcycles():
    edges = {k: set(v) for k, v in GRAPH.items()}
    edges["cnc_gym.errors"].add("cnc_gym.config")  # config imports errors: a two-module cycle
    assert any({"cnc_gym.errors", "cnc_gym.config"} <= c for c in cycles(edges))
    edges = {k: set(v) for k, v in GRAPH.items()}
    edges["cnc_gym.benchmark.suites"].add("cnc_gym.runner")
    edges["cnc_gym.runner"].add("cnc_gym.benchmark.metrics")
    assert cycles(_package_graph(edges))
    # The circle the package once had: the env's planner entry importing the learning code's package.
    edges = {k: set(v) for k, v in GRAPH.items()}
    edges["cnc_gym.envs.planner_prior"].add("cnc_gym_agents.training")
    assert any({"cnc_gym.envs", "cnc_gym_agents"} <= c for c in cycles(_package_graph(edges)))
