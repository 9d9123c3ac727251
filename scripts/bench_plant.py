"""Time the servo plant step and the contour-error meter on the hot path of an env step.

Usage: .venv/bin/python scripts/bench_plant.py [--machine vmc-small] [--ticks 5] [--envs 1 64] [--repeat N]

Prints microseconds per call (best of 5 runs of ``--repeat`` calls each):
- ``ServoPlant.step`` for each batch size in ``--envs`` with ``--ticks`` samples per call;
- ``ContourErrorMeter.measure`` for ``--ticks`` points on a path of lines and arcs (default window),
  and the reference service ``Toolpath.nearest`` on the same window for comparison.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import numpy as np

from cnc_gym.machine import DEFAULT_MACHINE, load_machine
from cnc_gym.plant import ContourErrorMeter, ServoPlant
from cnc_gym.toolpath import Plane, Toolpath, ToolpathBuilder


def best_time_us(call: Callable[[], object], repeat: int) -> float:
    best = math.inf
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(repeat):
            call()
        best = min(best, (time.perf_counter() - start) / repeat)
    return best * 1e6


def zigzag_with_arcs(passes: int = 20) -> Toolpath:
    """A pocket-like path: 40 mm passes joined by half-circle turns of radius 1 mm (step-over 2 mm)."""
    builder = ToolpathBuilder()
    builder.rapid((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), line=1)
    x, y = 0.0, 0.0
    for k in range(passes):
        x_end = 40.0 if k % 2 == 0 else 0.0
        builder.line((x, y, 0.0), (x_end, y, 0.0), feed=3000.0, line=k + 2)
        sweep = math.pi if k % 2 == 0 else -math.pi
        builder.arc((x_end, y, 0.0), (x_end, y + 2.0, 0.0), (x_end, y + 1.0, 0.0), Plane.XY, sweep,
                    feed=3000.0, line=k + 2)  # fmt: skip
        x, y = x_end, y + 2.0
    return builder.build()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machine", default=DEFAULT_MACHINE)
    parser.add_argument("--ticks", type=int, default=5, help="samples per call (control period / IPO)")
    parser.add_argument("--envs", type=int, nargs="+", default=[1, 64])
    parser.add_argument("--repeat", type=int, default=20000)
    args = parser.parse_args()

    machine = load_machine(args.machine)
    rng = np.random.default_rng(0)
    for n_envs in args.envs:
        plant = ServoPlant(machine, n_envs=n_envs)
        reference = rng.normal(0.0, 1.0, (n_envs, args.ticks, 3))
        plant.step(reference)  # builds and caches the lifted matrix for this tick count
        us = best_time_us(lambda p=plant, r=reference: p.step(r), args.repeat)
        print(f"ServoPlant.step          {args.machine:>10s}  {n_envs:4d} env x {args.ticks} ticks: "
              f"{us:7.2f} us/call  ({us / n_envs:6.2f} us per env)")  # fmt: skip

    toolpath = zigzag_with_arcs()
    meter = ContourErrorMeter(toolpath)
    hint = 10
    first, last = meter.window(hint)
    points = toolpath.evaluate(np.linspace(toolpath.s_start[hint], toolpath.s_start[hint + 1], args.ticks))[0]
    points = points + rng.normal(0.0, 0.01, points.shape)
    meter.measure(points, hint)
    us = best_time_us(lambda: meter.measure(points, hint), args.repeat)
    print(f"ContourErrorMeter.measure {args.ticks} points, window [{first}, {last}) "
          f"({last - first} segments, lines + arcs): {us:7.2f} us/call")  # fmt: skip
    us_ref = best_time_us(lambda: toolpath.nearest(points, first, last), max(1, args.repeat // 10))
    print(f"Toolpath.nearest (reference) same points and window:          {us_ref:7.2f} us/call")


if __name__ == "__main__":
    main()
