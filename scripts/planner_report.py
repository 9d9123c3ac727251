#!/usr/bin/env python3
"""How the deployable planner does against the oracle and constant overrides, from bench records.

    cnc-gym bench --split test --policy constant:0.5 ... --policy constant:1.0 --policy classical \\
        --policy oracle --policy bound --json test.jsonl
    .venv/bin/python scripts/planner_report.py test.jsonl [val.jsonl train.jsonl] [--policy classical]

Per file (one split or one set of ``--programs``), for the policy (default ``classical``): programs,
feasible share (finished with no path cut over tolerance), violations in total, episodes cut by the
step budget, the score, its mean time ratio against the bound and against the oracle's (the ratio of
the two means, as the leaderboard's columns give them, and the mean of per-program cycle-time ratios),
and how many programs it ran slower than the best feasible constant override among the records (the
grid is whatever ``constant:<x>`` policies the file holds; it is printed), with those programs named.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any


def load(path: Path) -> list[dict[str, Any]]:
    with path.open() as f:
        return [json.loads(line) for line in f if line.strip()]


def report(records: list[dict[str, Any]], policy: str) -> dict[str, Any]:
    """The figures above for ``policy`` over one file's records (seed 0 where there are several)."""
    by: dict[tuple[str, str], dict[str, Any]] = {}
    for r in records:
        if int(r.get("seed", 0)) == 0:
            by[(r["program"], r["policy"])] = r
    programs = sorted({p for p, _ in by})
    constants = sorted({q for _, q in by if q.startswith("constant:")}, key=lambda q: float(q.split(":")[1]))
    mine = [by[(p, policy)] for p in programs if (p, policy) in by]
    oracle = {p: by[(p, "oracle")] for p in programs if (p, "oracle") in by}
    out: dict[str, Any] = {"split": records[0].get("split"), "programs": len(mine), "constants": constants}
    out["feasible"] = sum(r["feasible"] for r in mine) / max(len(mine), 1)
    out["violations"] = sum(int(r["violations"] or 0) for r in mine)
    out["unfinished"] = [r["program"] for r in mine if not r["finished"]]
    out["infeasible"] = [r["program"] for r in mine if not r["feasible"]]
    out["score"] = 100.0 * sum(r["score"] for r in mine) / max(len(mine), 1)
    finished = [r for r in mine if r["finished"]]
    out["time_ratio"] = sum(r["time_ratio"] for r in finished) / max(len(finished), 1)
    if oracle:
        both = [r for r in finished if r["program"] in oracle and oracle[r["program"]]["finished"]]
        mean_oracle = sum(oracle[r["program"]]["time_ratio"] for r in both) / max(len(both), 1)
        out["oracle_time_ratio"] = mean_oracle
        out["vs_oracle_of_means"] = (sum(r["time_ratio"] for r in both) / max(len(both), 1)) / mean_oracle
        out["vs_oracle_per_program"] = sum(r["cycle_time_s"] / oracle[r["program"]]["cycle_time_s"]
                                           for r in both) / max(len(both), 1)  # fmt: skip
        out["oracle_feasible"] = sum(r["feasible"] for r in oracle.values()) / len(oracle)
    slower = []
    for r in mine:
        feasible = [by[(r["program"], q)] for q in constants
                    if (r["program"], q) in by and by[(r["program"], q)]["feasible"]]  # fmt: skip
        if not feasible:
            continue
        best = min(feasible, key=lambda c: c["cycle_time_s"])
        if not r["feasible"] or r["cycle_time_s"] > best["cycle_time_s"] * (1 + 1e-9):
            slower.append(f"{r['program']} ({r['cycle_time_s']:.2f} s vs {best['policy']} "
                          f"{best['cycle_time_s']:.2f} s)")  # fmt: skip
    out["slower_than_best_feasible_constant"] = slower
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("records", nargs="+", type=Path)
    parser.add_argument("--policy", default="classical")
    args = parser.parse_args(argv)
    for path in args.records:
        r = report(load(path), args.policy)
        print(f"{path.name}: split {r['split']}, {r['programs']} programs, policy {args.policy}")
        print(f"  feasible {100 * r['feasible']:.1f} %  violations {r['violations']}  "
              f"score {r['score']:.1f}  time ratio {r['time_ratio']:.3f}")  # fmt: skip
        if "oracle_time_ratio" in r:
            print(f"  oracle: time ratio {r['oracle_time_ratio']:.3f}, "
                  f"feasible {100 * r['oracle_feasible']:.1f} %; "
                  f"{args.policy}/oracle: {r['vs_oracle_of_means']:.3f} (of the means), "
                  f"{r['vs_oracle_per_program']:.3f} (mean per program)")  # fmt: skip
        print(f"  not finished: {r['unfinished'] or 'none'}; infeasible: {r['infeasible'] or 'none'}")
        grid = ", ".join(c.split(":")[1] for c in r["constants"]) or "none"
        slower = r["slower_than_best_feasible_constant"]
        print(f"  slower than the best feasible constant (grid {grid}): {len(slower)}")
        for line in slower:
            print(f"    {line}")
        if not math.isfinite(r["score"]):
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
