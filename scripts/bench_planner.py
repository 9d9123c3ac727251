#!/usr/bin/env python3
"""Cost of the deployable classical planner per segment, beside the oracle planner in the same process.

    .venv/bin/python scripts/bench_planner.py [--repeats 5] [--no-oracle]

Per family of the default suite's test split (all its programs), and on one long CAM-style program
(20 000 G01 chords), it times ``cnc_gym.motion.planner.plan_schedule`` (best of ``--repeats``), once with
the controller's static tables given (what the policy does: the env's controller already holds them) and once
computing them too, and divides by the number of motion segments. The oracle's planning (simulate and
correct on copies of the env) is timed once per family on the same programs, as the reference.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def long_cam_program(chords: int = 20_000) -> str:
    """A closed Lissajous-like curve as ``chords`` G01 moves of ~0.05 mm, coordinates rounded to 0.001."""
    lines = ["G90 G54 G17 G21", "S8000 M03", "G00 Z5.000", "G00 X20.000 Y0.000", "G00 Z1.000",
             "G01 Z-1.000 F600.000"]  # fmt: skip
    for k in range(1, chords + 1):
        t = 2 * math.pi * k / chords
        x, y = 20 * math.cos(t) + 3 * math.cos(7 * t), 15 * math.sin(2 * t) + 3 * math.sin(5 * t)
        lines.append(f"G01 X{x:.3f} Y{y:.3f}" + (" F3000.000" if k == 1 else ""))
    return "\n".join([*lines, "G00 Z5.000", "M05", "M30"]) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--no-oracle", action="store_true", help="skip the (slow) oracle reference")
    args = parser.parse_args(argv)

    import gymnasium

    import cnc_gym  # noqa: F401
    from cnc_gym.benchmark.suites import load_suite
    from cnc_gym.machine import load_machine
    from cnc_gym.motion.limits import build_limits
    from cnc_gym.motion.planner import plan_schedule
    from cnc_gym.policies.oracle import OraclePlanner
    from cnc_gym.programs import load_program

    machine = load_machine("vmc-small")
    suite = load_suite()
    groups: dict[str, list[str]] = {}
    for e in suite.programs("test"):
        groups.setdefault(e.family, []).append(e.text())
    groups["long CAM chain (20k G01)"] = [long_cam_program()]
    plan_schedule(*load_program("star", "gsk25i", machine)[1:], machine)  # compile the scan once
    print(f"{'programs':28s} {'n':>3s} {'segments':>9s} {'classical µs/seg':>17s} {'incl. limits':>13s} "
          f"{'oracle µs/seg':>14s} {'oracle/classical':>17s}")  # fmt: skip
    for family, texts in groups.items():
        toolpaths = [load_program(t, "gsk25i", machine)[1] for t in texts]
        limits = [build_limits(tp, machine) for tp in toolpaths]
        segments = sum(len(lim.seg_f) for lim in limits)
        best = best_full = math.inf
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            for tp, lim in zip(toolpaths, limits, strict=True):
                plan_schedule(tp, machine, limits=lim)
            t1 = time.perf_counter()
            for tp in toolpaths:
                plan_schedule(tp, machine)
            t2 = time.perf_counter()
            best, best_full = min(best, t1 - t0), min(best_full, t2 - t1)
        per, per_full = 1e6 * best / segments, 1e6 * best_full / segments
        oracle = ratio = "-"
        if not args.no_oracle and len(texts) <= 20:
            t0 = time.perf_counter()
            for text in texts:
                env = gymnasium.make("cnc_gym/Feedrate-v0", programs=[text], machine=machine)
                env.reset(seed=0)
                OraclePlanner(progress=False).reset(env)
                env.close()
            cost = 1e6 * (time.perf_counter() - t0) / segments
            oracle, ratio = f"{cost:.0f}", f"{cost / per:.0f}x"
        print(f"{family:28s} {len(texts):3d} {segments:9d} {per:17.2f} {per_full:13.2f} {oracle:>14s} "
              f"{ratio:>17s}", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
