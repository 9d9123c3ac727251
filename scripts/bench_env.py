#!/usr/bin/env python3
"""Benchmark ``cnc_gym/Feedrate-v0`` against ``Pendulum-v1`` in the same process.

Both envs are built with ``gymnasium.make`` (the same wrappers), driven with random actions, reset at
episode end; the two are timed in interleaved repeats and the median steps/s of each is reported with
their ratio (goal ≥ 1.0×, floor 0.3×). ``--vector N`` adds ``gymnasium.vector.SyncVectorEnv`` figures
(env-steps/s over N copies) for both and the native ``FeedrateVectorEnv`` of N copies; ``--profile``
prints where a Feedrate-v0 step spends its time.

Usage::

    .venv/bin/python scripts/bench_env.py                       # default program set, 5 repeats
    .venv/bin/python scripts/bench_env.py --vector 8 --json
    .venv/bin/python scripts/bench_env.py --profile --steps 3000
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import pstats
import statistics
import sys
import time

import gymnasium as gym
import numpy as np

import cnc_gym  # noqa: F401  (registers cnc_gym/Feedrate-v0)
from cnc_gym.envs.vector import FeedrateVectorEnv

FEEDRATE_ID = "cnc_gym/Feedrate-v0"
PENDULUM_ID = "Pendulum-v1"


def time_env(env: gym.Env, n_steps: int, seed: int) -> float:
    """Steps per second over ``n_steps`` random-action steps (resets included, as in training)."""
    env.reset(seed=seed)
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(n_steps)]
    start = time.perf_counter()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    return n_steps / (time.perf_counter() - start)


def time_vector(env: gym.vector.VectorEnv, n_steps: int, seed: int) -> float:
    """Env-steps per second (n_steps vector steps × num_envs)."""
    env.reset(seed=seed)
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(n_steps)]
    start = time.perf_counter()
    for action in actions:
        env.step(action)  # autoreset (next-step mode) handles episode ends
    return n_steps * env.num_envs / (time.perf_counter() - start)


def interleaved(make_a, make_b, timer, n_steps: int, repeats: int) -> tuple[list[float], list[float]]:
    env_a, env_b = make_a(), make_b()
    timer(env_a, min(200, n_steps), 0)  # warm-up: first-use caches (lifted matrices, look-ahead windows)
    timer(env_b, min(200, n_steps), 0)
    rates_a, rates_b = [], []
    for r in range(repeats):
        rates_a.append(timer(env_a, n_steps, r))
        rates_b.append(timer(env_b, n_steps, r))
    env_a.close()
    env_b.close()
    return rates_a, rates_b


def profile(kwargs: dict, n_steps: int, top: int) -> dict[str, float]:
    """cProfile a Feedrate-v0 run; print the top functions and return the share of each upstream call."""
    env = gym.make(FEEDRATE_ID, **kwargs)
    time_env(env, 200, 0)
    profiler = cProfile.Profile()
    profiler.enable()
    time_env(env, n_steps, 1)
    profiler.disable()
    stream = io.StringIO()
    stats = pstats.Stats(profiler, stream=stream).sort_stats("cumulative")
    stats.print_stats(top)
    print(stream.getvalue())
    total = max(s[3] for s in stats.stats.values())  # cumulative time of the outermost call
    shares = {}
    wanted = {
        "Controller.advance": ("advance",),
        "Controller.lookahead": ("lookahead",),
        "ServoPlant.step": ("step", "servo.py"),
        "ContourErrorMeter.measure": ("measure",),
        "FeedrateEnv.step (total)": ("step", "feedrate.py"),
        "FeedrateEnv._observe": ("_observe",),
        "FeedrateEnv._info": ("_info",),
    }
    for label, (func, *file_part) in wanted.items():
        cum = sum(
            s[3]
            for (filename, _, name), s in stats.stats.items()
            if name == func and (not file_part or file_part[0] in filename)
            and ("motion" in filename or "plant" in filename or "envs" in filename)
        )  # fmt: skip
        shares[label] = cum / total if total else 0.0
    print("share of the run's time (cumulative, profiler overhead included):")
    for label, share in shares.items():
        print(f"  {label:30s} {100 * share:5.1f} %")
    env.close()
    return shares


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000, help="steps per timed repeat (default 5000)")
    parser.add_argument("--repeats", type=int, default=5, help="interleaved repeats (default 5)")
    parser.add_argument("--program", action="append", help="program(s) for Feedrate-v0 (default: the set)")
    parser.add_argument("--vector", type=int, default=0, help="also time SyncVectorEnv with N copies")
    parser.add_argument("--profile", action="store_true", help="cProfile a Feedrate-v0 run")
    parser.add_argument("--json", action="store_true", help="print one JSON object at the end")
    args = parser.parse_args(argv)
    kwargs = {"programs": args.program} if args.program else {}

    feed_rates, pend_rates = interleaved(
        lambda: gym.make(FEEDRATE_ID, **kwargs),
        lambda: gym.make(PENDULUM_ID),
        time_env,
        args.steps,
        args.repeats,
    )
    result = {
        "feedrate_steps_per_s": statistics.median(feed_rates),
        "pendulum_steps_per_s": statistics.median(pend_rates),
        "repeats": args.repeats,
        "steps_per_repeat": args.steps,
        "programs": args.program or "default set",
    }
    result["ratio"] = result["feedrate_steps_per_s"] / result["pendulum_steps_per_s"]
    print(f"Feedrate-v0   {result['feedrate_steps_per_s']:10,.0f} steps/s  (repeats: "
          f"{', '.join(f'{r:,.0f}' for r in feed_rates)})")  # fmt: skip
    print(f"Pendulum-v1   {result['pendulum_steps_per_s']:10,.0f} steps/s  (repeats: "
          f"{', '.join(f'{r:,.0f}' for r in pend_rates)})")  # fmt: skip
    print(f"ratio         {result['ratio']:10.2f} ×  (goal ≥ 1.0, floor 0.3)")

    if args.vector:
        n = args.vector
        vec_steps = max(1, args.steps // n)
        feed_vec, pend_vec = interleaved(
            lambda: gym.vector.SyncVectorEnv([lambda: gym.make(FEEDRATE_ID, **kwargs)] * n),
            lambda: gym.vector.SyncVectorEnv([lambda: gym.make(PENDULUM_ID)] * n),
            time_vector,
            vec_steps,
            args.repeats,
        )
        native_vec, pend_vec2 = interleaved(
            lambda: FeedrateVectorEnv(n, **kwargs),
            lambda: gym.vector.SyncVectorEnv([lambda: gym.make(PENDULUM_ID)] * n),
            time_vector,
            vec_steps,
            args.repeats,
        )
        result["vector_envs"] = n
        result["feedrate_sync_vector_env_steps_per_s"] = statistics.median(feed_vec)
        result["pendulum_sync_vector_env_steps_per_s"] = statistics.median(pend_vec + pend_vec2)
        result["feedrate_native_vector_env_steps_per_s"] = statistics.median(native_vec)
        print(f"SyncVectorEnv ×{n} env-steps/s: Feedrate-v0 {statistics.median(feed_vec):,.0f}, "
              f"Pendulum-v1 {result['pendulum_sync_vector_env_steps_per_s']:,.0f}")  # fmt: skip
        print(f"FeedrateVectorEnv ×{n} env-steps/s: {statistics.median(native_vec):,.0f} "
              f"({statistics.median(native_vec) / statistics.median(feed_vec):.2f} × SyncVectorEnv)")

    if args.profile:
        result["profile_shares"] = profile(kwargs, args.steps, 25)
    if args.json:
        print(json.dumps(result, default=float))
    return 0


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    sys.exit(main())
