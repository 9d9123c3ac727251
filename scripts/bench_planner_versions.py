#!/usr/bin/env python3
"""CPU time per segment of every version of the deployable planner (the live one and the frozen ones), in
one process.

    .venv/bin/python scripts/bench_planner_versions.py [--repeats 3]

Per family of the default suite's test split, and on one CAM chain of 20 000 G01 moves
(``bench_planner.long_cam_program``), it times each version's schedule function
(:data:`cnc_gym.motion.planner.PLANNERS`) with the controller's static tables given (what the policy does),
as CPU time of this process (``time.process_time``, best of ``--repeats``), so that other jobs on the
machine inflate it less than wall time, and divides by the number of motion segments. The last row is the
test split's mean: all its CPU time over all its segments.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    from bench_planner import long_cam_program

    from cnc_gym.benchmark.suites import load_suite
    from cnc_gym.machine import load_machine
    from cnc_gym.motion.limits import build_limits
    from cnc_gym.motion.planner import PLANNERS
    from cnc_gym.programs import load_program

    machine = load_machine("vmc-small")
    versions = sorted(PLANNERS, reverse=True)
    groups: dict[str, list[str]] = {}
    for e in load_suite().programs("test"):
        groups.setdefault(e.family, []).append(e.text())
    families = set(groups)
    groups["long CAM chain (20k G01)"] = [long_cam_program()]
    star = load_program("star", "gsk25i", machine)[1]
    for v in versions:  # compile each once
        PLANNERS[v][0](star, machine)
    print(f"{'programs':28s} {'segments':>9s}" + "".join(f"{f'v{v} µs/seg (CPU)':>16s}" for v in versions))
    split_segments, split_seconds = 0, [0.0] * len(versions)  # over the whole test split
    for family, texts in groups.items():
        toolpaths = [load_program(t, "gsk25i", machine)[1] for t in texts]
        limits = [build_limits(tp, machine) for tp in toolpaths]
        segments = sum(len(lim.seg_f) for lim in limits)
        costs = []
        for v in versions:
            plan, margin = PLANNERS[v]
            best = float("inf")
            for _ in range(args.repeats):
                t0 = time.process_time()
                for tp, lim in zip(toolpaths, limits, strict=True):
                    plan(tp, machine, limits=lim, margin=margin)
                best = min(best, time.process_time() - t0)
            costs.append(1e6 * best / segments)
        print(f"{family:28s} {segments:9d}" + "".join(f"{c:16.2f}" for c in costs), flush=True)
        if family in families:
            split_segments += segments
            split_seconds = [t + c * segments for t, c in zip(split_seconds, costs, strict=True)]
    print(f"{'test split, all programs':28s} {split_segments:9d}"
          + "".join(f"{t / split_segments:16.2f}" for t in split_seconds))  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
