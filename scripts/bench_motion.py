#!/usr/bin/env python3
"""Benchmark the controller (``cnc_gym.motion.Controller``).

Reports, for a program (the built-in suite by default, or a seeded random 3-D polyline with arcs):

* construction time (static limits for every segment and junction);
* ``advance(5) + lookahead()`` per call, the env's control step (5 interpolation periods = 10 ms): the
  target is ≲ 30 µs together;
* ``advance()`` throughput in interpolation periods per second for chunks of 5 and of 4096;
* real-time factor (simulated seconds per wall second) for a whole run at 100 %.

The first call compiles the numba kernels (cached on disk after that); it is excluded from the timings.

Usage::

    .venv/bin/python scripts/bench_motion.py                   # built-in programs
    .venv/bin/python scripts/bench_motion.py --random 5000     # random program of 5000 blocks
    .venv/bin/python scripts/bench_motion.py --json
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np

from cnc_gym.machine import DEFAULT_MACHINE, load_machine
from cnc_gym.motion import Controller
from cnc_gym.toolpath import Plane, Toolpath, ToolpathBuilder


def random_toolpath(n_blocks: int, seed: int = 0) -> Toolpath:
    """Lines (random 3-D directions) and XY arcs, feeds 1000–9000 mm/min, no stops."""
    rng = np.random.default_rng(seed)
    b = ToolpathBuilder()
    p = np.zeros(3)
    for line in range(1, n_blocks + 1):
        feed = float(rng.uniform(1000, 9000))
        if rng.random() < 0.3:
            r = float(rng.uniform(1.0, 10.0))
            phi = rng.uniform(-math.pi, math.pi)
            c = p - r * np.array([math.cos(phi), math.sin(phi), 0.0])
            sweep = float(rng.uniform(0.2, 2.0) * rng.choice([-1, 1]))
            q = np.array([c[0] + r * math.cos(phi + sweep), c[1] + r * math.sin(phi + sweep), p[2]])
            b.arc(tuple(p), tuple(q), tuple(c), Plane.XY, sweep, feed=feed, line=line)
        else:
            q = p + rng.normal(size=3) * np.array([3.0, 3.0, 0.3])
            b.line(tuple(p), tuple(q), feed=feed, line=line)
        p = q
    return b.build()


def builtin_toolpaths() -> dict[str, Toolpath]:
    from cnc_gym.programs import load_program, program_names

    return {name: load_program(name)[1] for name in program_names()}


def bench(name: str, tp: Toolpath, machine_name: str, calls: int) -> dict:
    machine = load_machine(machine_name)
    Controller(tp, machine).run_to_end()  # compile / load the kernels
    t0 = time.perf_counter()
    # No servo here to report "in position", so the stops must not wait for one.
    controller = Controller(tp, machine, in_position_check=False)
    build_s = time.perf_counter() - t0

    rng = np.random.default_rng(1)
    knobs = rng.uniform(0.2, 2.0, size=calls)
    t0 = time.perf_counter()
    for knob in knobs:
        controller.advance(5, override=float(knob))
        if controller.finished:
            controller.reset()
    advance5_s = (time.perf_counter() - t0) / calls
    t0 = time.perf_counter()
    for _ in range(calls):
        controller.lookahead(20.0, 16)
    lookahead_s = (time.perf_counter() - t0) / calls

    controller.reset()
    t0 = time.perf_counter()
    chunk = controller.run_to_end()
    run_s = time.perf_counter() - t0
    return {
        "program": name,
        "machine": machine_name,
        "segments": len(tp),
        "build_ms": 1e3 * build_s,
        "advance5_us": 1e6 * advance5_s,
        "lookahead_us": 1e6 * lookahead_s,
        "step_us": 1e6 * (advance5_s + lookahead_s),
        "ticks_per_s_chunk5": 5 / advance5_s,
        "ticks_per_s_chunk4096": len(chunk) / run_s,
        "cycle_time_s": float(chunk.time_s[-1]),
        "realtime_factor": float(chunk.time_s[-1]) / run_s,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--random", type=int, default=0, help="bench a random program of N blocks instead")
    parser.add_argument("--machine", default=DEFAULT_MACHINE)
    parser.add_argument("--calls", type=int, default=20000, help="advance(5)/lookahead calls to time")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.random:
        programs = {f"random-{args.random}": random_toolpath(args.random)}
    else:
        try:
            programs = builtin_toolpaths()
        except Exception as exc:  # the interpreter is another stage; keep the benchmark usable without it
            print(f"built-in programs unavailable ({exc}); using a random 1000-block program",
                  file=sys.stderr)
            programs = {"random-1000": random_toolpath(1000)}
    results = [bench(name, tp, args.machine, args.calls) for name, tp in programs.items()]
    if args.json:
        print(json.dumps(results, indent=2))
        return
    print(f"{'program':<14}{'segs':>7}{'build ms':>10}{'adv(5) µs':>11}{'lookahead µs':>14}{'step µs':>9}"
          f"{'ticks/s (5)':>13}{'ticks/s (4096)':>16}{'cycle s':>9}{'× real time':>13}")  # fmt: skip
    for r in results:
        print(f"{r['program']:<14}{r['segments']:>7}{r['build_ms']:>10.2f}{r['advance5_us']:>11.2f}"
              f"{r['lookahead_us']:>14.2f}{r['step_us']:>9.2f}{r['ticks_per_s_chunk5']:>13.3g}"
              f"{r['ticks_per_s_chunk4096']:>16.3g}{r['cycle_time_s']:>9.2f}"
              f"{r['realtime_factor']:>13.0f}")  # fmt: skip


if __name__ == "__main__":
    main()
