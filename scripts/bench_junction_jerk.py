#!/usr/bin/env python3
"""The finite-difference jerk at junctions: GSK's per-axis step (``corner_rule: step``) against the
jerk-limited corner rule (``corner_rule: jerk``) on random programs (docs/motion.md §7).

The jerk is the third difference of the reference positions at the interpolation period T,
(p(t+T) − 3p(t) + 3p(t−T) − p(t−2T))/T³, over the whole run (at rest before the start and after the end),
as a share of the limit it should keep:

* **polylines**: random 3-D G01 chains (turns from float noise to reversals, segments of 3 µm–20 mm, feeds
  of 300–12 000 mm/min) on a machine with unequal axis jerks (50 000, 20 000, 8 000 mm/s³); the largest
  |jerk_k| / J_k over the axes;
* **line/arc chains**: random XY chains of lines and arcs (tangent joins, gentle and sharp kinks) on a
  machine whose path-norm jerk binds (9 000 mm/s³); the largest ‖jerk‖ / J_path.

Each at a random constant override in 0.3–2.0, both rules on the same programs; the cycle time ratio is
jerk rule ÷ step rule. ``tests/motion/test_motion_junction_jerk.py`` draws its programs from the same
generators.

Usage::

    .venv/bin/python scripts/bench_junction_jerk.py              # 200 programs of each family
    .venv/bin/python scripts/bench_junction_jerk.py --programs 50 --blocks 30
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from cnc_gym.machine import MachineConfig, machine_from_dict
from cnc_gym.motion import Controller, MotionChunk
from cnc_gym.toolpath import Plane, Toolpath, ToolpathBuilder

AXIS_JERK = np.array([50000.0, 20000.0, 8000.0])
PATH_JERK = 9000.0


def axis_machine(rule: str) -> MachineConfig:
    """Unequal axes (jerk, acceleration), a 16-block window."""
    return machine_from_dict({
        "name": "jerk-axes", "controller": {"corner_rule": rule, "lookahead_blocks": 16},
        "axes": {"x": {"max_jerk_mm_s3": AXIS_JERK[0]},
                 "y": {"max_jerk_mm_s3": AXIS_JERK[1], "max_accel_mm_s2": 2000},
                 "z": {"max_jerk_mm_s3": AXIS_JERK[2], "max_accel_mm_s2": 1000}},
    })  # fmt: skip


def path_norm_machine(rule: str) -> MachineConfig:
    """Per-axis limits well above the path-norm ones (800 mm/s², 9 000 mm/s³), so that the norms bind."""
    return machine_from_dict({
        "name": "jerk-norm",
        "controller": {"max_centripetal_accel_mm_s2": 50000, "path_max_accel_mm_s2": 800,
                       "path_max_jerk_mm_s3": PATH_JERK, "corner_rule": rule},
        "axis_defaults": {"max_accel_mm_s2": 20000, "max_jerk_mm_s3": 500000, "rapid_accel_mm_s2": 20000,
                          "rapid_jerk_mm_s3": 500000, "corner_step_mm_min": 300},
    })  # fmt: skip


def random_polyline(rng: np.random.Generator, n: int) -> Toolpath:
    """3-D G01 chains: turns from float noise to reversals, segments from 3 µm to 20 mm."""
    b = ToolpathBuilder()
    p = np.zeros(3)
    d = np.array([1.0, 0.0, 0.0])
    for line in range(1, n + 1):
        turn = float(rng.choice([0.0, 1e-13, 1e-3, 1e-2, 0.05, 0.2, 1.0, 3.0])) * rng.random()
        d = d + rng.normal(size=3) * turn
        d /= np.linalg.norm(d)
        q = p + d * 10 ** rng.uniform(-2.5, 1.3)
        b.line(tuple(p), tuple(q), feed=float(rng.uniform(300.0, 12000.0)), line=line)
        p = q
    return b.build()


def random_chain(rng: np.random.Generator, n: int) -> Toolpath:
    """XY chains of lines and arcs: tangent joins (curvature jumps only), gentle and sharp kinks."""
    b = ToolpathBuilder()
    p = np.zeros(3)
    heading = 0.0
    for line in range(1, n + 1):
        if rng.random() < 0.5:
            heading += float(rng.choice([0.0, 0.0, 1e-3, 0.05, 0.5, 2.0]) * rng.normal())
        feed = float(rng.uniform(300.0, 12000.0))
        if rng.random() < 0.5:
            q = p + 10 ** rng.uniform(-2.0, 1.3) * np.array([math.cos(heading), math.sin(heading), 0.0])
            b.line(tuple(p), tuple(q), feed=feed, line=line)
        else:
            radius = 10 ** rng.uniform(-1.0, 1.3)
            side = float(rng.choice([-1.0, 1.0]))
            sweep = side * float(rng.uniform(0.05, 3.0))
            center = p + radius * side * np.array([-math.sin(heading), math.cos(heading), 0.0])
            phi = math.atan2(p[1] - center[1], p[0] - center[0]) + sweep
            q = center + radius * np.array([math.cos(phi), math.sin(phi), 0.0])
            b.arc(tuple(p), tuple(q), tuple(center), Plane.XY, sweep, feed=feed, line=line)
            heading += sweep
        p = q
    return b.build()


def finite_difference_jerk(tp: Toolpath, chunk: MotionChunk, period_s: float) -> np.ndarray:
    """Third differences of the reference positions over a whole run from reset (at rest at the program start
    before it, at rest at the end after it), / T³: (n + 3, 3)."""
    start = tp.start[:1]
    pos = np.vstack((np.repeat(start, 3, axis=0), chunk.position, np.repeat(chunk.position[-1:], 3, axis=0)))
    return np.diff(pos, 3, axis=0) / period_s**3


def measure(family: str, programs: int, blocks: int) -> dict[str, dict[str, float]]:
    """Per rule: the worst jerk share over the programs, and the summed cycle time."""
    make, machine_of = {"polylines": (random_polyline, axis_machine),
                        "chains": (random_chain, path_norm_machine)}[family]  # fmt: skip
    out: dict[str, dict[str, float]] = {}
    for rule in ("step", "jerk"):
        machine = machine_of(rule)
        period = machine.controller.interpolation_period_s
        worst, cycle = 0.0, 0.0
        for seed in range(programs):
            rng = np.random.default_rng(seed)
            tp = make(rng, blocks)
            override = float(rng.uniform(0.3, 2.0))
            chunk = Controller(tp, machine, in_position_check=False).run_to_end(override=override)
            jerk = finite_difference_jerk(tp, chunk, period)
            share = (np.max(np.abs(jerk) / AXIS_JERK) if family == "polylines"
                     else np.max(np.linalg.norm(jerk, axis=1)) / PATH_JERK)  # fmt: skip
            worst = max(worst, float(share))
            cycle += float(chunk.time_s[-1])
        out[rule] = {"worst_share": worst, "cycle_s": cycle}
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--programs", type=int, default=200, help="programs per family (seeds 0..N-1)")
    parser.add_argument("--blocks", type=int, default=20, help="blocks per program")
    args = parser.parse_args(argv)
    print(f"{'family':10s} {'step: worst jerk / limit':>25s} {'jerk rule: worst jerk / limit':>31s} "
          f"{'cycle jerk ÷ step':>18s}")  # fmt: skip
    for family in ("polylines", "chains"):
        r = measure(family, args.programs, args.blocks)
        print(f"{family:10s} {r['step']['worst_share']:25.2f} {r['jerk']['worst_share']:31.9f} "
              f"{r['jerk']['cycle_s'] / r['step']['cycle_s']:18.2f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
