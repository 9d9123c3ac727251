#!/usr/bin/env python3
"""Time the contour-error meter's compiled kernel alone, on the calls of real episodes, per program family.

The calls are recorded from Feedrate-v0 episodes (random actions) on the modular step, whose contour error
is one ``ContourErrorMeter.measure`` call per env step; then ``measure_kernel`` is replayed on them the way
the fused step calls it: from compiled code, on borrowed arrays (no reference counts), with no Python in
between. Prints µs per call (the best of ``--repeats`` replays; one call per env step, five plant samples) and
what a call costs over one of the ``flat`` family in the same process (the step's share of the family's
slow-down). The families are those of ``scripts/bench_env.py``.

Usage::

    .venv/bin/python scripts/bench_contour.py                        # flat, helix, nurbs; 4000 steps each
    .venv/bin/python scripts/bench_contour.py --steps 2000 --repeats 5
    PYTHONPATH=<checkout of a commit> .venv/bin/python scripts/bench_contour.py --save /tmp/before
    .venv/bin/python scripts/bench_contour.py --against /tmp/before   # how far the contour errors moved
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_env import FAMILIES, run_single, sampled

from cnc_gym.envs.engine.bank import borrowed as lent
from cnc_gym.envs.feedrate import FeedrateEnv
from cnc_gym.plant import ContourErrorMeter, ServoPlant
from cnc_gym.plant.contour import measure_kernel


class _ModularPlant(ServoPlant):
    compiled_step = False


class _ModularEnv(FeedrateEnv):
    def make_batch(self, n_envs, parallel=None, plant=None):
        return super().make_batch(n_envs, parallel, _ModularPlant(self.machine, n_envs))


def record(family: str, steps: int) -> list[tuple[ContourErrorMeter, np.ndarray, np.ndarray, np.ndarray]]:
    """Per meter: (meter, points (m, 3), hints, call offsets) of ``steps`` env steps on ``family``."""
    calls: dict[int, tuple[ContourErrorMeter, list, list]] = {}
    original = ContourErrorMeter.measure

    def recording(self, points, segment_hint):
        entry = calls.setdefault(id(self), (self, [], []))
        entry[1].append(np.array(points, dtype=np.float64).reshape(-1, 3))
        entry[2].append(np.atleast_1d(np.asarray(segment_hint, dtype=np.int64)))
        return original(self, points, segment_hint)

    programs = FAMILIES[family]()
    ContourErrorMeter.measure = recording
    try:
        env = _ModularEnv(**({} if programs is None else {"programs": programs}))
        run_single(env, sampled(env.action_space, steps, 2), 2)
    finally:
        ContourErrorMeter.measure = original
    out = []
    for meter, points, hints in calls.values():
        offsets = np.zeros((len(points) + 1, 2), dtype=np.int64)
        offsets[1:, 0] = np.cumsum([len(p) for p in points])
        offsets[1:, 1] = np.cumsum([len(h) for h in hints])
        out.append((meter, np.concatenate(points), np.concatenate(hints), offsets))
    return out


@njit(nogil=True)  # (no disk cache: it would keep the kernel of whichever checkout compiled it first)
def _replay(points, hints, offsets, seg_class, axes, geometry, first_back, nurbs_f, nurbs_i, ahead, out):
    points, hints, out, seg_class, axes = lent(points), lent(hints), lent(out), lent(seg_class), lent(axes)
    geometry, first_back, nurbs_f, nurbs_i = lent(geometry), lent(first_back), lent(nurbs_f), lent(nurbs_i)
    for c in range(offsets.shape[0] - 1):
        p0, p1, h0, h1 = offsets[c, 0], offsets[c + 1, 0], offsets[c, 1], offsets[c + 1, 1]
        measure_kernel(points[p0:p1], hints[h0:h1], seg_class, axes, geometry, first_back, nurbs_f, nurbs_i,
                       ahead, out[p0:p1])  # fmt: skip


def replay_us(recorded, repeats: int) -> tuple[float, int, list[np.ndarray]]:
    """(best µs per call over ``repeats`` replays, calls, the contour errors of each meter's calls)."""
    n_calls = sum(len(offsets) - 1 for _, _, _, offsets in recorded)
    outs = [np.empty(len(points)) for _, points, _, _ in recorded]

    def replay() -> None:
        for (meter, points, hints, offsets), out in zip(recorded, outs, strict=True):
            _replay(points, hints, offsets, *meter.tables, meter.window_ahead, out)  # the kernel's order

    replay()
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        replay()
        best = min(best, time.perf_counter() - start)
    return 1e6 * best / n_calls, n_calls, outs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--families", nargs="+", default=list(FAMILIES), choices=list(FAMILIES))
    parser.add_argument("--steps", type=int, default=4000, help="env steps recorded per family")
    parser.add_argument("--repeats", type=int, default=9, help="replays; the best one counts (default 9)")
    parser.add_argument("--save", metavar="DIR", type=Path, help="write each family's points and errors")
    parser.add_argument("--against", metavar="DIR", type=Path,
                        help="compare the errors with those --save wrote in DIR")  # fmt: skip
    args = parser.parse_args(argv)
    recorded = {family: record(family, args.steps) for family in args.families}
    times = {}
    for family, calls in recorded.items():
        times[family] = replay_us(calls, args.repeats)
        points = np.concatenate([p for _, p, _, _ in calls])
        errors = np.concatenate(times[family][2])
        if args.save:
            args.save.mkdir(parents=True, exist_ok=True)
            np.savez(args.save / f"{family}.npz", points=points, errors=errors)
        if args.against:
            saved = np.load(args.against / f"{family}.npz")
            if saved["points"].shape != points.shape or not np.array_equal(saved["points"], points):
                print(f"{family}: the recorded points differ from those in {args.against}")
            else:
                moved = np.abs(errors - saved["errors"])
                print(f"{family}: contour errors moved by at most {moved.max():.2e} mm "
                      f"({int(np.count_nonzero(moved))} of {moved.size} samples moved)")  # fmt: skip
    flat = times["flat"][0] if "flat" in times else None
    print(f"{'family':8s} {'calls':>7s} {'µs/call':>9s} {'over flat':>10s}")
    for family, (us, n_calls, _) in times.items():
        over = f"{us - flat:+10.3f}" if flat is not None else f"{'-':>10s}"
        print(f"{family:8s} {n_calls:7d} {us:9.3f} {over}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
