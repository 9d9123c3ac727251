"""Every program of the test suite, the docs and the built-in programs gives the tool path it gave when the
snapshot was taken (``scripts/gcode_snapshot.py``; see its docstring for what is in it).

The snapshot was taken before the interpreter was split into ``lang/`` and ``dialects/``: this test is
what says that redesign changed no tool path and no error. A deliberate change of behaviour regenerates
it (``capture`` then ``generate``) in the same commit as the change.
"""

from __future__ import annotations

import gzip
import json

from snapshot_tools import SNAPSHOT, run_input


def test_every_snapshot_program_gives_the_same_outcome() -> None:
    with gzip.open(SNAPSHOT, "rt") as source:
        entries = json.load(source)
    assert len(entries) > 3000
    mismatches = []
    for entry in entries:
        expected = {key: entry[key] for key in ("segments", "digest", "error") if key in entry}
        got = run_input(entry)
        if got != expected:
            mismatches.append((entry["options"], entry["text"][:200], expected, got))
    report = "\n\n".join(f"options {o}\n{t}\nexpected {e}\ngot      {g}" for o, t, e, g in mismatches[:5])
    assert not mismatches, f"{len(mismatches)} of {len(entries)} programs changed:\n\n{report}"
