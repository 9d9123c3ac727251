#!/usr/bin/env python3
"""Write the leaderboard table of docs/benchmark.md from ``cnc-gym bench`` JSON Lines records.

    .venv/bin/python scripts/leaderboard.py docs/results/cnc-bench-v1-test.jsonl [more.jsonl ...]
    .venv/bin/python scripts/leaderboard.py docs/results/cnc-bench-v1-test.jsonl --check   # CI: up to date?
    .venv/bin/python scripts/leaderboard.py RECORDS.jsonl --print                          # to stdout only
    .venv/bin/python scripts/leaderboard.py RECORDS.jsonl --plot docs/images/benchmark     # and the plots

Records from several files (people, runs, an RL agent's ``cnc-gym bench --policy model.zip --json``)
merge into one table when they share suite, split and machine. See cnc_gym/benchmark/leaderboard.py.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from cnc_gym.errors import CncGymError

DOC = Path(__file__).resolve().parent.parent / "docs" / "benchmark.md"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("records", nargs="+", help="bench JSON Lines files")
    parser.add_argument("--doc", default=str(DOC), help="document to update (default docs/benchmark.md)")
    parser.add_argument("--check", action="store_true", help="exit 1 if the document's table is out of date")
    parser.add_argument("--print", action="store_true", help="print the table, touch no file")
    parser.add_argument("--plot", metavar="DIR", help="also write pareto.png and families.png into DIR")
    args = parser.parse_args(argv)
    try:
        from cnc_gym.benchmark.leaderboard import render_markdown, replace_between_markers, update_document
        from cnc_gym.benchmark.runner import read_jsonl

        records = read_jsonl(args.records)
        table = render_markdown(records, args.records)
        if args.plot:
            from cnc_gym.benchmark.plots import write_plots

            first = records[0]
            write_plots(records, args.plot, title=f"{first['suite']} {first['split']}")
        if args.print:
            print(table, end="")
            return 0
        if args.check:
            text = Path(args.doc).read_text()
            if replace_between_markers(text, table, args.doc) != text:
                print(f"{args.doc}: the leaderboard is out of date; run scripts/leaderboard.py "
                      f"{' '.join(args.records)}", file=sys.stderr)  # fmt: skip
                return 1
            return 0
        changed = update_document(args.doc, table)
    except (CncGymError, OSError) as exc:
        print(f"leaderboard: {exc}", file=sys.stderr)
        return 2
    print(f"{args.doc}: {'updated' if changed else 'already up to date'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
