"""Write (or check) the docs' error-code tables from the registry, so the docs never drift from the code.

    .venv/bin/python scripts/error_code_docs.py           # rewrite the tables in place
    .venv/bin/python scripts/error_code_docs.py --check   # exit 1 and name the file if a table differs

A table sits in a Markdown file between ``<!-- error-codes NAME -->`` and ``<!-- end error-codes -->``;
NAME is a key of :data:`TABLES`, which maps it to the scopes of :mod:`cnc_gym.error_codes` it lists.
``tests/test_error_codes.py`` runs the check.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from doc_blocks import block_renderer, update_docs

from cnc_gym.error_codes import Scope, markdown_table

REPO = Path(__file__).resolve().parent.parent
#: Table name → the scopes it lists.
TABLES: dict[str, tuple[Scope, ...]] = {
    "gcode": (Scope.GCODE,),
    "dialects": (Scope.FANUC, Scope.SYNTEC, Scope.H4CM),
    "notes": (Scope.NOTE,),
    "din": (Scope.DIN,),
    "motion": (Scope.MOTION,),
}
#: Files that hold tables.
DOCS = ("docs/gcode.md", "docs/azmc1.md", "docs/motion.md")
#: ``text`` with every table block rewritten, and the names of the blocks found.
render = block_renderer("error-codes", {name: (lambda scopes=scopes: markdown_table(*scopes))
                                         for name, scopes in TABLES.items()}, "error_code_docs")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="report differences instead of writing")
    args = parser.parse_args(argv)
    stale, found = update_docs(REPO, DOCS, render, args.check)
    missing = sorted(set(TABLES) - set(found))
    if missing:
        print(f"error_code_docs: no block for table(s) {', '.join(missing)} in {', '.join(DOCS)}",
              file=sys.stderr)  # fmt: skip
        return 1
    listed = {scope for name in found for scope in TABLES[name]}
    if set(Scope) - listed:
        print(f"error_code_docs: no table lists scope(s) {sorted(s.value for s in set(Scope) - listed)}",
              file=sys.stderr)  # fmt: skip
        return 1
    if stale and args.check:
        print(f"error_code_docs: stale table(s) in {', '.join(stale)}; run scripts/error_code_docs.py",
              file=sys.stderr)  # fmt: skip
        return 1
    for doc in stale:
        print(f"rewrote {doc}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
