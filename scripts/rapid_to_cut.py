#!/usr/bin/env python3
"""Show what happens, control step by step, where a program's first cut follows a rapid.

    .venv/bin/python scripts/rapid_to_cut.py [PROGRAM] [--machine vmc-small] [--before 5] [--after 4]

Every built-in program approaches with a rapid to Z4 and plunges at F600. The controller holds the
plunge until the axes are in position (P1471 ``in_position_mm``); this prints, around that moment, the
reference segment, whether the controller is waiting, the actual position, following error and speed, and
the contour error of the step under both rules of the meter: ``cuts`` (cutting moves only, as
``cnc_gym/Feedrate-v0`` and ``-v1`` are registered) and ``path`` (the programmed path, with the rapid the
reference has left; ``cnc_gym/Feedrate-v2``, ``cnc-gym run`` and ``cnc-gym bench``). The two envs run in
lockstep: the rule changes the measurement, not the motion (docs/plant.md, "Contour error at a rapid →
cut junction").
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def main(argv: list[str] | None = None) -> int:
    from cnc_gym.envs.feedrate import FeedrateEnv
    from cnc_gym.errors import CncGymError
    from cnc_gym.machine import DEFAULT_MACHINE
    from cnc_gym.toolpath import SegmentKind

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("program", nargs="?", default="circle")
    parser.add_argument("--machine", default=DEFAULT_MACHINE)
    parser.add_argument("--before", type=int, default=5, help="control steps shown before the first cut")
    parser.add_argument("--after", type=int, default=4, help="control steps shown after it")
    args = parser.parse_args(argv)
    try:
        env = FeedrateEnv(programs=[args.program], machine=args.machine, contour_rule="cuts")
        env_path = FeedrateEnv(programs=[args.program], machine=args.machine, contour_rule="path")
    except CncGymError as exc:
        print(f"rapid_to_cut: {exc}", file=sys.stderr)
        return 2
    env.reset(seed=0)
    env_path.reset(seed=0)
    kind = env.toolpath.kind
    cutting = (kind == SegmentKind.LINE) | (kind == SegmentKind.ARC) | (kind == SegmentKind.NURBS)
    rows, first_cut = [], None
    action = np.zeros(1, dtype=np.float32)  # 100 % override
    terminated = truncated = False
    while not (terminated or truncated) and (first_cut is None or len(rows) < first_cut + args.after + 1):
        _, _, terminated, truncated, info = env.step(action)
        info_path = env_path.step(action)[-1]
        segment = env.controller.segment_index
        rows.append((info["cycle_time_s"], segment, "cut" if cutting[segment] else "rapid",
                     env.controller.waiting_in_position, env.plant.position[0].copy(),
                     float(np.linalg.norm(env.plant.following_error[0])),
                     float(np.linalg.norm(env.plant.velocity[0])), info["contour_error_mm"],
                     info_path["contour_error_mm"]))  # fmt: skip
        if first_cut is None and cutting[segment]:
            first_cut = len(rows) - 1
    if first_cut is None:
        print(f"{args.program}: no cutting move")
        return 0
    kv = min(env.machine.axis_array("kv_1_s"))
    print(f"{args.program} on {args.machine}: in-position width {env.in_position_mm * 1000:g} µm, settled "
          f"below {kv * env.in_position_mm:.2f} mm/s (min Kv x width); contour tolerance "
          f"{env.tolerance_mm * 1000:g} µm")  # fmt: skip
    print(f"{'t s':>6} {'seg':>3} {'ref on':>6} {'wait':>5} {'actual X, Y, Z (mm)':>28} "
          f"{'follow µm':>9} {'mm/s':>7} {'cuts µm':>8} {'path µm':>8}")  # fmt: skip
    for t, seg, on, wait, pos, follow, speed, error, error_path in rows[max(first_cut - args.before, 0):]:
        xyz = ", ".join(f"{v:.5f}" for v in pos)
        print(f"{t:6.2f} {seg:3d} {on:>6} {'yes' if wait else 'no':>5} {xyz:>28} {follow * 1000:9.2f} "
              f"{speed:7.3f} {error * 1000:8.3f} {error_path * 1000:8.3f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
