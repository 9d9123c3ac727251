"""The layout of ``cnc_gym/gcode`` is its architecture: no import cycles, and the core knows no feature.

Imports are read from the source (``ast``), all of them: module level, inside functions, and under
``if TYPE_CHECKING:``. ``from package import module`` is an import of that module (as Python resolves it);
``from package import name`` of a name the package's ``__init__`` defines is an import of the package.
"""

from __future__ import annotations

import ast
from pathlib import Path

import cnc_gym.gcode

ROOT = Path(cnc_gym.gcode.__file__).resolve().parent
PREFIX = "cnc_gym.gcode"
#: The core: the contract, the state, the output boundary and the block executor. They name no language
#: family and no dialect (those plug in through the Dialect record).
CORE = {"codes", "settings", "program", "offsets", "canonical", "state", "dialect", "interpreter"}


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join([PREFIX, *parts])] = path
    return out


MODULES = _modules()


def _imports(name: str, path: Path) -> set[str]:
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
    return {m for m in found if m in MODULES and m != name}


GRAPH = {name: _imports(name, path) for name, path in MODULES.items()}


def _cycle() -> list[str] | None:
    state: dict[str, int] = {}  # 1 visiting, 2 done
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(GRAPH[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt):], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(GRAPH):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_the_package_has_the_layout_of_the_architecture():
    assert f"{PREFIX}.lang.fanuc" in MODULES and f"{PREFIX}.dialects.gsk25i" in MODULES
    assert f"{PREFIX}.dialects.fanuc" in MODULES
    assert all(f"{PREFIX}.{core}" in MODULES for core in CORE)


def test_no_import_cycles_in_gcode_type_checking_imports_included():
    cycle = _cycle()
    assert cycle is None, "import cycle: " + " → ".join(cycle or [])


def test_the_core_imports_no_language_family_and_no_dialect():
    for core in CORE:
        plug_ins = (f"{PREFIX}.lang", f"{PREFIX}.dialects")
        bad = sorted(m for m in GRAPH[f"{PREFIX}.{core}"] if m.startswith(plug_ins))
        assert not bad, f"{core}.py imports {bad}"


def test_features_see_the_core_only_through_the_seam():
    # Language parts and dialects never import the interpreter module: they get the core as a Seam.
    for name, imports in GRAPH.items():
        if name.startswith((f"{PREFIX}.lang", f"{PREFIX}.dialects")):
            assert f"{PREFIX}.interpreter" not in imports, name


def test_dialect_folders_do_not_import_each_other():
    for name, imports in GRAPH.items():
        if name.startswith(f"{PREFIX}.dialects."):
            own = ".".join(name.split(".")[:4])
            other = sorted(m for m in imports
                           if m.startswith(f"{PREFIX}.dialects.") and not m.startswith(own))  # fmt: skip
            assert not other, f"{name} imports another dialect: {other}"


def test_the_cycle_check_finds_a_cycle():
    # The check itself can fail: a two-module cycle planted in a copy of the graph is found.
    saved = {k: set(v) for k, v in GRAPH.items()}
    try:
        GRAPH[f"{PREFIX}.codes"].add(f"{PREFIX}.interpreter")
        assert _cycle() is not None
    finally:
        GRAPH.clear()
        GRAPH.update(saved)
