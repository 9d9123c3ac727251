"""The generated blocks of the docs, rewritten in place or checked: the loop that
``scripts/config_docs.py`` and ``scripts/error_code_docs.py`` share (each renders its own blocks)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path


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
