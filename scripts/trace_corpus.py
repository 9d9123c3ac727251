#!/usr/bin/env python3
"""Trace every program file of a folder with ``cnc-gym trace`` and print what traced and what was refused.

A measurement for a corpus of real programs (shop programs, CAM output, manual examples): each file runs
through the command a user runs (``cnc-gym trace FILE --dialect fanuc``, in a fresh process, so that a
crash or a hang shows as one), and the table gives, per file, ``traced`` (exit 0, with the number of
motions and any warning on stderr), ``refused`` (exit 2, with the error code and the message) or
``CRASH`` (any other exit status, a Python traceback, or more than ``--timeout`` seconds). The counts
at the end are the figures to compare before and after a change.

Subprograms the programs call (``M98 P3003``, ``G65 P9001``) are found in the program's own folder, or
in ``--program-dir``; files there are not traced themselves.

Usage::

    .venv/bin/python scripts/trace_corpus.py CORPUS_DIR                          # --dialect fanuc
    .venv/bin/python scripts/trace_corpus.py CORPUS_DIR --program-dir CORPUS_DIR/support --json out.jsonl
    .venv/bin/python scripts/trace_corpus.py CORPUS_DIR -- --calculator-input    # extra trace options
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

_TRACE = "import sys; from cnc_gym.cli import main; sys.argv[0] = 'cnc-gym'; sys.exit(main())"
_CODE = re.compile(r"\[([a-z0-9/+-]+)\]\s*$")


def trace_one(path: Path, options: list[str], timeout: float) -> dict:
    """Run ``cnc-gym trace`` on one file; return its record (file, outcome, code, motions, message)."""
    command = [sys.executable, "-c", _TRACE, "trace", str(path), *options]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"file": path.name, "outcome": "CRASH", "code": "timeout", "motions": 0,
                "message": f"no answer within {timeout:g} s"}  # fmt: skip
    stderr = done.stderr.strip()
    last = stderr.splitlines()[-1] if stderr else ""
    if done.returncode == 0:
        motions = sum(1 for line in done.stdout.splitlines() if line.strip())
        return {"file": path.name, "outcome": "traced", "code": "", "motions": motions, "message": last}
    if done.returncode == 2 and "Traceback" not in stderr:
        match = _CODE.search(last)
        return {"file": path.name, "outcome": "refused", "code": match.group(1) if match else "?",
                "motions": 0, "message": last}  # fmt: skip
    return {"file": path.name, "outcome": "CRASH", "code": f"exit {done.returncode}", "motions": 0,
            "message": last}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=Path, help="folder of program files (not searched recursively)")
    parser.add_argument("--dialect", default="fanuc", help="dialect to trace with (default fanuc)")
    parser.add_argument("--program-dir", type=Path, default=None,
                        help="where called programs are found (default: each program's folder)")  # fmt: skip
    parser.add_argument("--timeout", type=float, default=60.0,
                        help="seconds per file before it counts as a hang")  # fmt: skip
    parser.add_argument("--json", type=Path, default=None, help="also write one JSON record per file")
    argv = list(sys.argv[1:] if argv is None else argv)
    # Everything after '--' goes to cnc-gym trace as it is (split here: argparse would bind an empty
    # list of extra positionals to the folder's chunk and then refuse the options after '--').
    extra = argv[argv.index("--") + 1 :] if "--" in argv else []
    argv = argv[: argv.index("--")] if "--" in argv else argv
    parser.epilog = "Options after -- are passed to cnc-gym trace (e.g. -- --calculator-input)."
    args = parser.parse_args(argv)
    if not args.folder.is_dir():
        parser.error(f"{args.folder}: not a folder")
    options = ["--dialect", args.dialect, *extra]
    if args.program_dir is not None:
        options += ["--program-dir", str(args.program_dir)]
    files = sorted(p for p in args.folder.iterdir() if p.is_file() and not p.name.startswith("."))
    records = []
    width = max((len(p.name) for p in files), default=4)
    for path in files:
        record = trace_one(path, options, args.timeout)
        records.append(record)
        detail = f"{record['motions']} motions" if record["outcome"] == "traced" else record["code"]
        note = record["message"] if record["outcome"] != "traced" or record["message"] else ""
        print(f"{record['file']:<{width}}  {record['outcome']:<7}  {detail:<22}  {note[:160]}", flush=True)
    outcomes = Counter(r["outcome"] for r in records)
    codes = Counter(r["code"] for r in records if r["outcome"] == "refused")
    print(f"\n{len(records)} files: {outcomes['traced']} traced, {outcomes['refused']} refused, "
          f"{outcomes['CRASH']} crashed")  # fmt: skip
    if codes:
        print("refused by code: " + ", ".join(f"{code} {n}" for code, n in codes.most_common()))
    if args.json is not None:
        args.json.write_text("".join(json.dumps(r) + "\n" for r in records))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
