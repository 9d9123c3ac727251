"""A policy against a baseline, program by program, from `cnc-gym bench` records.

    .venv/bin/python scripts/compare_records.py RECORDS.jsonl [...] --policy SPEC [--baseline classical]
        [--markdown]

For every (programs, machine, track) of the records (programs: the suite's split, or ``user`` for
``--programs`` files): how many programs the policy ran, the mean over them of its
and the baseline's cycle time (each program's mean over seeds), on how many programs its mean cycle time
is below / above the baseline's (0.1 % either way counts as equal), the mean of
the per-program time ratios policy / baseline, and every program where the policy fails the baseline's
standard: a violation (any seed) where the baseline is feasible, or a mean cycle time above the
baseline's. docs/training.md's generalisation table is this script's ``--markdown`` output.
"""

from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from cnc_gym.benchmark.runner import read_jsonl
from cnc_gym.errors import CncGymError

#: Relative difference of mean cycle times below which two policies count as equally fast.
EQUAL = 1e-3


def compare(records: list[dict[str, Any]], policy: str, baseline: str) -> list[dict[str, Any]]:
    """One row per (programs, machine, track): the counts of the module docstring and the failing
    programs."""
    groups: dict[tuple[str, str, str], dict[str, dict[str, list[dict[str, Any]]]]] = defaultdict(
        lambda: defaultdict(lambda: defaultdict(list))
    )
    for r in records:
        if r.get("reference") or r["policy"] not in (policy, baseline):
            continue
        source = "user" if r.get("suite", "user") == "user" else f"{r['suite']}/{r.get('split')}"
        groups[(source, r["machine"], r.get("track", "nominal"))][r["program"]][r["policy"]].append(r)
    rows = []
    for (source, machine, track), programs in sorted(groups.items()):
        faster = slower = 0
        ratios: list[float] = []
        times = [0.0, 0.0]  # sums of the policy's and the baseline's mean cycle times
        failures: list[str] = []
        both = {name: runs for name, runs in programs.items() if policy in runs and baseline in runs}
        if not both:
            continue
        for name, runs in sorted(both.items()):
            mine = sum(r["cycle_time_s"] for r in runs[policy]) / len(runs[policy])
            base = sum(r["cycle_time_s"] for r in runs[baseline]) / len(runs[baseline])
            ratios.append(mine / base)
            times[0] += mine
            times[1] += base
            if mine < base * (1 - EQUAL):
                faster += 1
            elif mine > base * (1 + EQUAL):
                slower += 1
                failures.append(f"{name} slower ({mine / base:.3f} ×)")
            base_clean = all(r["feasible"] for r in runs[baseline])
            violating = sum(not r["feasible"] for r in runs[policy])
            if base_clean and violating:
                failures.append(f"{name} adds a violation ({violating} of {len(runs[policy])} seeds)")
        rows.append({"programs_from": source, "machine": machine, "track": track, "programs": len(both),
                     "faster": faster,
                     "slower": slower, "mean_ratio": sum(ratios) / len(ratios) if ratios else float("nan"),
                     "mean_time_s": times[0] / max(len(both), 1),
                     "baseline_time_s": times[1] / max(len(both), 1),
                     "failures": failures})  # fmt: skip
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("records", nargs="+", help="bench records (JSON Lines)")
    parser.add_argument("--policy", required=True, help="the policy's name in the records")
    parser.add_argument("--baseline", default="classical", help="the baseline's name (default classical)")
    parser.add_argument("--markdown", action="store_true", help="a Markdown table")
    args = parser.parse_args(argv)
    try:
        records = read_jsonl([Path(p) for p in args.records])
    except CncGymError as exc:
        print(exc, file=sys.stderr)
        return 2
    rows = compare(records, args.policy, args.baseline)
    if not rows:
        print(f"no programs with both {args.policy!r} and {args.baseline!r}", file=sys.stderr)
        return 1
    if args.markdown:
        print(f"| programs | machine | track | count | mean cycle time (s): policy / {args.baseline} | "
              f"faster / slower | mean time ratio to {args.baseline} | where it fails |")  # fmt: skip
        print("|---|---|---|---:|---:|---:|---:|---|")
    for r in rows:
        failing = "; ".join(r["failures"]) or "none"
        if args.markdown:
            print(f"| {r['programs_from']} | `{r['machine']}` | {r['track']} | {r['programs']} | "
                  f"{r['mean_time_s']:.2f} / "
                  f"{r['baseline_time_s']:.2f} | {r['faster']} / {r['slower']} | {r['mean_ratio']:.3f} | "
                  f"{failing} |")  # fmt: skip
        else:
            print(f"{r['programs_from']:<20} {r['machine']:<12} {r['track']:<9} programs {r['programs']:>3}  "
                  f"mean time {r['mean_time_s']:.2f} s against {r['baseline_time_s']:.2f} s  "
                  f"faster {r['faster']:>3}  slower {r['slower']:>3}  "
                  f"mean ratio {r['mean_ratio']:.3f}  fails: {failing}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
