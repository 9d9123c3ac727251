"""The generated blocks of the docs, rewritten in place or checked: the loop that
``scripts/config_docs.py`` and ``scripts/error_code_docs.py`` share (each renders its own blocks)."""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path


def block_renderer(marker: str, tables: Mapping[str, Callable[[], str]],
                   tool: str) -> Callable[[str], tuple[str, list[str]]]:  # fmt: skip
    """A ``render`` for :func:`update_docs`: every block between ``<!-- MARKER NAME -->`` and
    ``<!-- end MARKER -->`` rewritten as ``tables[NAME]()``; an unknown NAME stops ``tool`` with one line."""
    block = re.compile(rf"(<!-- {marker} ([\w.]+) -->\n)(.*?)(<!-- end {marker} -->)", re.S)

    def render(text: str) -> tuple[str, list[str]]:
        names: list[str] = []

        def fill(match: re.Match[str]) -> str:
            name = match.group(2)
            if name not in tables:
                raise SystemExit(f"{tool}: unknown table {name!r} (known: {', '.join(tables)})")
            names.append(name)
            return f"{match.group(1)}{tables[name]()}\n{match.group(4)}"

        return block.sub(fill, text), names

    return render


def update_docs(repo: Path, docs: Iterable[str], render: Callable[[str], tuple[str, list[str]]],
                check: bool) -> tuple[list[str], list[str]]:  # fmt: skip
    """Render every doc of ``docs`` (paths under ``repo``); write the changed ones unless ``check``.
    Returns the docs that were stale and the names of the blocks found."""
    stale: list[str] = []
    found: list[str] = []
    for doc in docs:
        path = repo / doc
        text = path.read_text()
        new, names = render(text)
        found += names
        if new != text:
            stale.append(doc)
            if not check:
                path.write_text(new)
    return stale, found
