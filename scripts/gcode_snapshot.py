"""Tool-path snapshot of every program the test suite, the docs and the built-in programs interpret.

    .venv/bin/python scripts/gcode_snapshot.py capture     # run the suite, record every interpret() input
    .venv/bin/python scripts/gcode_snapshot.py generate    # interpret each input, write the snapshot

The snapshot (``tests/gcode/snapshots/toolpaths.json.gz``) holds, per program, the inputs of one
``interpret()`` call (text, file name, dialect name, machine preset name, options) and a digest of the
resulting tool path (every array of the ``Toolpath``, rounded to 1e-9, NURBS curves included) or the
error line it raised. ``tests/gcode/test_snapshot.py`` re-runs them all and compares: a refactoring of
``cnc_gym/gcode`` must leave every digest unchanged. Regenerate only for an intended change of
behaviour, and say so in the commit.

``capture`` wraps ``cnc_gym.gcode.interpret`` while the test suite runs (``CI=true``, so the property
tests draw the same examples every time) and keeps the calls whose options can be written down: dialect
by name, machine by preset name, plain data for the rest. Calls with dialect variants built in a test or
machines changed in a test are left out (their own tests cover them). The built-in programs
(``cnc_gym/programs``) and the G-code blocks of the docs and README are added to the same list.
"""

from __future__ import annotations

import ast
import dataclasses
import gzip
import json
import math
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(ROOT / "tests" / "gcode"))

from snapshot_tools import SNAPSHOT, run_input  # noqa: E402

CAPTURED = Path(tempfile.gettempdir()) / "cnc_gym_snapshot_inputs.jsonl"  # capture → generate
#: Longest program text kept (the speed benchmarks' 100 000-line programs are not snapshot material).
MAX_TEXT = 60_000


# --------------------------------------------------------------------------- capture
def _plain(value):
    """A literal that ast.literal_eval reads back, or raise TypeError."""
    if isinstance(value, float) and not math.isfinite(value):
        raise TypeError("non-finite float")  # repr() would not read back
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, frozenset | set):
        return sorted(_plain(v) for v in value)
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, dict) or hasattr(value, "items"):
        return {_plain(k): _plain(v) for k, v in value.items()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    raise TypeError(type(value).__name__)


def _options(kwargs: dict) -> str | None:
    """The call's options as a literal, or None where one cannot be written down faithfully."""
    from cnc_gym.gcode import get_dialect
    from cnc_gym.machine import MachineConfig, load_machine, machine_names

    out = {}
    for key, value in kwargs.items():
        if key == "dialect":
            if not isinstance(value, str):
                try:
                    if value is not get_dialect(value.name):
                        return None
                except Exception:
                    return None
                value = value.name
        elif key == "machine":
            if value is None:
                continue
            if not isinstance(value, MachineConfig):
                return None
            name = next((n for n in machine_names() if load_machine(n) == value), None)
            if name is None:
                return None
            value = name
        elif key == "program_dir":
            if value is not None:
                return None
            continue
        elif key == "tool_offsets" and value is not None and not isinstance(value, dict):
            return None
        elif key == "file" and ("/" in value or os.sep in value):
            value = Path(value).name  # a test's temporary file: the name alone, so reruns agree
        try:
            out[key] = _plain(value)
        except TypeError:
            return None
    return repr(out)


class _Recorder:
    """pytest plugin: wraps cnc_gym.gcode.interpret for the whole session."""

    def __init__(self) -> None:
        self.seen: set[tuple] = set()
        self.skipped = 0
        self.out = CAPTURED.open("w")

    def pytest_configure(self, config) -> None:
        import cnc_gym.gcode as gcode

        original = gcode.interpret

        def interpret(text, **kwargs):
            try:
                options = _options(kwargs) if isinstance(text, str) and len(text) <= MAX_TEXT else None
                if options is None:
                    self.skipped += 1
                elif (text, options) not in self.seen:
                    self.seen.add((text, options))
                    self.out.write(json.dumps({"text": text, "options": options}) + "\n")
            except Exception:  # recording must never change what the tests see
                self.skipped += 1
            return original(text, **kwargs)

        gcode.interpret = interpret

    def pytest_unconfigure(self, config) -> None:
        self.out.close()
        print(f"\nsnapshot capture: {len(self.seen)} programs, {self.skipped} calls left out",
              file=sys.stderr)


def _doc_programs() -> list[dict]:
    """Built-in programs, and fenced blocks of the docs and README that are G-code."""
    from cnc_gym.programs import program_path  # noqa: F401  (the package of built-in programs)

    items = []
    for path in sorted((ROOT / "cnc_gym" / "programs").rglob("*.nc")):
        items.append({"text": path.read_text(), "options": repr({"file": path.name})})
    fence = re.compile(r"```[a-z]*\n(.*?)```", re.S)
    gcode_line = re.compile(r"^\s*(%|[OoNnGgMm#(/]\S*|[XYZxyz]-?\d)")
    for doc in sorted([ROOT / "README.md", *(ROOT / "docs").glob("*.md")]):
        for block in fence.findall(doc.read_text()):
            lines = [line for line in block.splitlines() if line.strip()]
            if lines and all(gcode_line.match(line) for line in lines):
                items.append({"text": block, "options": repr({"file": doc.name})})
    return items


def capture() -> int:
    import pytest

    recorder = _Recorder()
    os.environ["CI"] = "true"
    code = pytest.main(["-q", "-p", "no:cacheprovider", "-x", str(ROOT / "tests")], plugins=[recorder])
    with CAPTURED.open("a") as out:
        for item in _doc_programs():
            out.write(json.dumps(item) + "\n")
    return int(code)


def generate() -> int:
    items = []
    for line in CAPTURED.read_text().splitlines():
        item = json.loads(line)
        try:
            ast.literal_eval(item["options"])
        except ValueError:
            continue  # a non-finite number slipped through an older capture
        items.append(item)
    # #3011/#3012 read the date and the time of day: such a program's path is not reproducible.
    unique = {(i["text"], i["options"]): i for i in items
              if "#3011" not in i["text"] and "#3012" not in i["text"]}  # fmt: skip
    entries = []
    for item in sorted(unique.values(), key=lambda i: (i["options"], i["text"])):
        entries.append({**item, **run_input(item)})
    SNAPSHOT.parent.mkdir(parents=True, exist_ok=True)
    data = json.dumps(entries, separators=(",", ":"), sort_keys=True).encode()
    with SNAPSHOT.open("wb") as raw, gzip.GzipFile(fileobj=raw, mode="wb", compresslevel=9, mtime=0) as out:
        out.write(data)  # mtime 0: the same snapshot gives the same bytes
    errors = sum("error" in e for e in entries)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()  # fmt: skip
    print(f"{len(entries)} programs ({errors} raise an error) -> {SNAPSHOT.relative_to(ROOT)} at {commit}")
    return 0


if __name__ == "__main__":
    command = sys.argv[1] if len(sys.argv) > 1 else ""
    if command == "capture":
        raise SystemExit(capture())
    if command == "generate":
        raise SystemExit(generate())
    print(__doc__)
    raise SystemExit(2)
