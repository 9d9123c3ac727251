"""The import graph of a source tree, read with ``ast``: what the layout tests check.

All imports count: module level, inside functions, and under ``if TYPE_CHECKING:``. ``from package import
module`` is an import of that module (as Python resolves it); ``from package import name`` of a name the
package's ``__init__`` defines is an import of the package.
"""

from __future__ import annotations

import ast
from pathlib import Path


def modules(roots: dict[Path, str]) -> dict[str, Path]:
    """Module name → source file, for every ``*.py`` under each root folder (imported by the given name)."""
    out = {}
    for root, name in roots.items():
        for path in sorted(root.rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([name, *parts])] = path
    return out


def imported_names(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """Every module name the source of ``name`` imports (resolved against ``known``, not filtered)."""
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
                found.add(candidate if candidate in known else base)
    return found


def graph(known: dict[str, Path]) -> dict[str, set[str]]:
    """Module → the modules of ``known`` it imports."""
    return {name: {m for m in imported_names(name, path, known) if m in known and m != name}
            for name, path in known.items()}  # fmt: skip


def cycles(edges: dict[str, set[str]]) -> list[set[str]]:
    """The import cycles: strongly connected components of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(edges.get(node, ())):
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

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return found
