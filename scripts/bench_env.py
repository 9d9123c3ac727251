#!/usr/bin/env python3
"""Benchmark the feed-rate envs against ``Pendulum-v1`` in the same process.

Every figure is a ratio against Pendulum-v1 (``gymnasium.make``, random actions) timed in the same
process, interleaved with it, so that a noisy machine moves both alike; each is the median over
``--repeats`` repeats, in wall time and in CPU time (``time.process_time``: the process's own CPU
seconds, all threads; steadier than wall time on a shared machine, larger than it when threads run).

- **single**: every registered ``cnc_gym/Feedrate-*`` id through ``gymnasium.make`` (its wrappers
  included), steps/s; resets at episode ends are part of the run, as in training;
- **vector**: the native vector env of each id of ``--vector-ids`` (default: v0 and the newest; built by
  ``gymnasium.make_vec(id, N, vectorization_mode="vector_entry_point")``) at N ∈ ``--envs`` (default 1, 8,
  64, 256), env-steps/s (N × steps/s) against Pendulum-v1's single-env steps/s; each repeat runs from a
  reset for at least ``--vector-steps`` steps (default 1500), so that every env runs whole episodes (500 to
  1400 steps with random actions on the three families), not only the rapid and the plunge they start with;
  ``--parallel`` picks numba's threads (``auto``: the env's default rule; ``both``: each N serial and in
  threads);
- program families (``--families``): ``flat`` (the built-in set: lines and flat arcs), ``helix`` (a
  helical bore, one G03 block per half turn), ``nurbs`` (a chain of cubic G06.2 curves);
- **plants** (``--plants``): ``cnc_gym/Feedrate-v0`` on ``vmc-small-mujoco`` with ``plant="lti"`` and
  ``plant="mujoco"`` (the same machine, loops and programs; docs/plant.md), single env and
  ``FeedrateVectorEnv(8)``, each against Pendulum-v1 and the MuJoCo figure against the LTI one;
- **build**: the time to construct ``FeedrateVectorEnv(64)`` (compiled code loaded from the disk cache);
- ``--profile``: where a step spends its time: cProfile of the Python layers around the one compiled call
  of ``--profile-env`` (default Feedrate-v0; actions sampled beforehand, not counted), and the compiled
  work of a Feedrate-v0 step split into its parts
  (controller periods, servo plant, contour error, the rest), timed by running the same episode through
  the modular step, whose parts are separate calls.

Usage::

    .venv/bin/python scripts/bench_env.py                     # everything, 5 repeats
    .venv/bin/python scripts/bench_env.py --quick             # fewer steps and repeats
    .venv/bin/python scripts/bench_env.py --families flat --envs 64 --json out.json
    .venv/bin/python scripts/bench_env.py --profile --families flat helix
    .venv/bin/python scripts/bench_env.py --families flat --envs --plants   # only the plants
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import math
import pstats
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym

import cnc_gym  # noqa: F401  (registers the cnc_gym/Feedrate-* ids)
from cnc_gym.envs.vector import FeedrateVectorEnv

PENDULUM_ID = "Pendulum-v1"


# -------------------------------------------------------------------------------------------- programs
def helix_program(turns: int = 12, radius: float = 8.0, pitch: float = 0.5, feed: float = 3000.0) -> str:
    """A helical bore: ``turns`` turns of ``pitch`` mm, one G03 block per half turn."""
    lines = ["G90 G21 G17", f"G00 X{radius:.4f} Y0 Z1", "G01 Z0 F600"]
    z = 0.0
    for k in range(2 * turns):
        z -= pitch / 2
        x = -radius if k % 2 == 0 else radius
        lines.append(f"G03 X{x:.4f} Y0 Z{z:.4f} I{x:.4f} J0 F{feed:.0f}")
    return "\n".join([*lines, "G00 Z5", "M30"]) + "\n"


def nurbs_program(curves: int = 8, feed: float = 2400.0) -> str:
    """A chain of ``curves`` cubic NURBS (G05 P10000 / G06.2), each 7 control points of a wave, 40 mm long."""
    lines = ["G90 G21 G17", "G00 X0 Y0 Z1", "G01 Z0 F600", "G05 P10000"]
    knots = [0, 0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1, 1]
    x0 = 0.0
    for c in range(curves):
        side = 1.0 if c % 2 else -1.0
        points = [(x0 + 40.0 * i / 6, side * 6.0 * math.sin(math.pi * i / 3)) for i in range(7)]
        points[0] = (x0, 0.0)
        points[-1] = (x0 + 40.0, 0.0)
        for i, (x, y) in enumerate(points):
            head = f"G06.2 P4 F{feed:.0f} " if i == 0 else ""
            lines.append(f"{head}K{knots[i]} X{x:.4f} Y{y:.4f} R1.0")
        lines += [f"K{k}" for k in knots[7:]]
        x0 += 40.0
    lines += [f"G01 X{x0:.4f} Y2", "G05 P0", "G00 Z5", "M30"]
    return "\n".join(lines) + "\n"


FAMILIES: dict[str, Callable[[], list[str] | None]] = {
    "flat": lambda: None,  # the env's default set: circle, star, freeform, pocket
    "helix": lambda: [helix_program()],
    "nurbs": lambda: [nurbs_program()],
}


# ---------------------------------------------------------------------------------------------- timing
def run_single(env: gym.Env, actions: list, seed: int) -> tuple[float, float]:
    """(wall s, CPU s) of ``len(actions)`` steps, resets at episode ends included."""
    env.reset(seed=seed)
    wall, cpu = time.perf_counter(), time.process_time()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    return time.perf_counter() - wall, time.process_time() - cpu


def run_vector(env: gym.vector.VectorEnv, actions: list, seed: int) -> tuple[float, float]:
    """(wall s, CPU s) of ``len(actions)`` vector steps (next-step autoreset)."""
    env.reset(seed=seed)
    wall, cpu = time.perf_counter(), time.process_time()
    for action in actions:
        env.step(action)
    return time.perf_counter() - wall, time.process_time() - cpu


def sampled(space: gym.Space, n: int, seed: int) -> list:
    space.seed(seed)
    return [space.sample() for _ in range(n)]


def against_pendulum(env, runner, n_steps: int, env_steps_per_step: int, repeats: int) -> dict[str, float]:
    """Rates of ``env`` and Pendulum-v1 in interleaved repeats; medians and ratios (wall and CPU)."""
    pendulum = gym.make(PENDULUM_ID)
    space = env.action_space
    warm = sampled(space, min(200, n_steps), 99)
    runner(env, warm, 99)  # first-use costs (compiled code, program packing)
    run_single(pendulum, sampled(pendulum.action_space, 200, 99), 99)
    rates: dict[str, list[float]] = {"wall": [], "cpu": [], "p_wall": [], "p_cpu": []}
    for r in range(repeats):
        actions = sampled(space, n_steps, r)
        wall, cpu = runner(env, actions, r)
        rates["wall"].append(n_steps * env_steps_per_step / wall)
        rates["cpu"].append(n_steps * env_steps_per_step / max(cpu, 1e-9))
        p_actions = sampled(pendulum.action_space, 4 * n_steps // max(1, env_steps_per_step) + 2000, r)
        wall, cpu = run_single(pendulum, p_actions, r)
        rates["p_wall"].append(len(p_actions) / wall)
        rates["p_cpu"].append(len(p_actions) / max(cpu, 1e-9))
    pendulum.close()
    out = {key: statistics.median(values) for key, values in rates.items()}
    out["ratio_wall"] = out["wall"] / out["p_wall"]
    out["ratio_cpu"] = out["cpu"] / out["p_cpu"]
    return out


# ------------------------------------------------------------------------------------------- profiles
def profile_layers(env_id: str, kwargs: dict, n_steps: int) -> list[tuple[str, float]]:
    """cProfile of ``n_steps`` steps through gym.make: each function's own time per step (µs), largest
    first. The compiled call appears as one entry (``run_serial``)."""
    env = gym.make(env_id, **kwargs)
    actions = sampled(env.action_space, n_steps, 1)
    run_single(env, actions[:200], 0)
    env.reset(seed=1)
    profiler = cProfile.Profile()
    profiler.enable()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    profiler.disable()
    stats = pstats.Stats(profiler, stream=io.StringIO())
    rows = []
    for (filename, _, name), (_, _, tottime, _, _) in stats.stats.items():
        where = Path(filename).name if filename != "~" else "builtin"
        rows.append((f"{name} ({where})", 1e6 * tottime / n_steps))
    env.close()
    return sorted(rows, key=lambda r: -r[1])


def profile_compiled_parts(kwargs: dict, n_steps: int) -> dict[str, float]:
    """µs per step of each compiled part, measured on the modular step (same numbers, separate calls)."""
    from cnc_gym.envs.engine import batch
    from cnc_gym.envs.feedrate import FeedrateEnv
    from cnc_gym.motion import Controller
    from cnc_gym.plant import ContourErrorMeter, ServoPlant

    class _Plant(ServoPlant):
        compiled_step = False

    class _Env(FeedrateEnv):
        def make_batch(self, n_envs, parallel=None, plant=None):
            return super().make_batch(n_envs, parallel, _Plant(self.machine, n_envs))

    totals = {"controller periods": 0.0, "servo plant": 0.0, "contour error": 0.0,
              "statistics, reward, observation": 0.0}  # fmt: skip
    originals = (Controller.advance_rows, ServoPlant.step, ServoPlant.settled, ContourErrorMeter.measure,
                 batch.finish_modular)  # fmt: skip

    def timed(label, fn):
        def wrapper(*args, **kwargs):
            start = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                totals[label] += time.perf_counter() - start
        return wrapper

    Controller.advance_rows = timed("controller periods", originals[0])
    ServoPlant.step = timed("servo plant", originals[1])
    ServoPlant.settled = timed("servo plant", originals[2])
    ContourErrorMeter.measure = timed("contour error", originals[3])
    batch.finish_modular = timed("statistics, reward, observation", originals[4])
    try:
        env = _Env(**kwargs)
        actions = sampled(env.action_space, n_steps, 2)
        run_single(env, actions[:200], 0)
        for key in totals:
            totals[key] = 0.0
        run_single(env, actions, 2)
    finally:
        (Controller.advance_rows, ServoPlant.step, ServoPlant.settled, ContourErrorMeter.measure,
         batch.finish_modular) = originals  # fmt: skip
    return {key: 1e6 * value / n_steps for key, value in totals.items()}


# ---------------------------------------------------------------------------------------------- main
def compare_plants(args: argparse.Namespace, show: Callable[[str, dict], None]) -> list[dict]:
    """Feedrate-v0 on vmc-small-mujoco with the LTI and the MuJoCo plant (single env and 8 envs), against
    Pendulum-v1, and MuJoCo's rate over LTI's (the MuJoCo runs take a quarter of the steps)."""
    rows = []
    for family in args.families:
        programs = FAMILIES[family]()
        kwargs = {"machine": "vmc-small-mujoco", **({} if programs is None else {"programs": programs})}
        for n in (1, 8):
            rates = {}
            for plant in ("lti", "mujoco"):
                steps = max(50, args.steps // (4 if plant == "mujoco" else 1) // n)
                if n == 1:
                    env = gym.make("cnc_gym/Feedrate-v0", plant=plant, **kwargs)
                    r = against_pendulum(env, run_single, steps, 1, args.repeats)
                    label = f"Feedrate-v0 {plant}"
                else:
                    env = FeedrateVectorEnv(n, plant=plant, **kwargs)
                    r = against_pendulum(env, run_vector, steps, n, args.repeats)
                    label = f"FeedrateVectorEnv({n}) {plant}"
                env.close()
                show(f"{label} [{family}, vmc-small-mujoco]", r)  # the same machine on either plant
                rates[plant] = r
                rows.append({"plant": plant, "envs": n, "family": family, **r})
            slower = rates["lti"]["wall"] / rates["mujoco"]["wall"]
            print(f"{'':46s} the MuJoCo plant: {slower:.0f}× fewer steps/s than the LTI plant "
                  f"(CPU time: {rates['lti']['cpu'] / rates['mujoco']['cpu']:.0f}×)")
    return rows


def make_vector(env_id: str, n: int, kwargs: dict, parallel: bool | None) -> gym.vector.VectorEnv:
    """The id's native vector env of ``n`` envs: its vector entry point where it has one (v0 alone had one
    before every id got its own, so older checkouts still run: FeedrateVectorEnv for v0)."""
    extra = {} if parallel is None else {"parallel": parallel}
    if gym.spec(env_id).vector_entry_point is not None:
        return gym.make_vec(env_id, n, vectorization_mode="vector_entry_point", **kwargs, **extra)
    return FeedrateVectorEnv(n, **kwargs, **extra)


def feedrate_ids() -> list[str]:
    return sorted(env_id for env_id in gym.registry if env_id.startswith("cnc_gym/Feedrate"))


def build_time(n_envs: int) -> float:
    """Seconds to construct FeedrateVectorEnv(n_envs) in a fresh process (compiled code from the cache)."""
    code = ("import time, cnc_gym.envs.vector as v; v.FeedrateVectorEnv(2); t = time.perf_counter(); "
            f"v.FeedrateVectorEnv({n_envs}); print(time.perf_counter() - t)")  # fmt: skip
    return float(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                                text=True).stdout.split()[-1])  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=4000,
                        help="env steps per timed repeat (vector: divided by N)")  # fmt: skip
    parser.add_argument("--repeats", type=int, default=5, help="interleaved repeats (default 5)")
    parser.add_argument("--families", nargs="+", default=list(FAMILIES), choices=list(FAMILIES))
    parser.add_argument("--envs", type=int, nargs="*", default=[1, 8, 64, 256], help="vector env sizes")
    parser.add_argument("--vector-steps", type=int, default=1500,
                        help="at least this many vector steps per timed repeat (default 1500: every env runs "
                             "a whole episode of each family, not only the rapid and plunge it starts with)")
    parser.add_argument("--parallel", choices=["auto", "on", "off", "both"], default="auto")
    parser.add_argument("--vector-ids", nargs="+", default=None, choices=feedrate_ids(), metavar="ID",
                        help="ids whose vector env to time (default: v0 and the newest id)")
    parser.add_argument("--profile", action="store_true", help="profile a step (see above)")
    parser.add_argument("--profile-env", default="cnc_gym/Feedrate-v0", choices=feedrate_ids(),
                        help="the id whose Python layers --profile times (default cnc_gym/Feedrate-v0)")
    parser.add_argument("--quick", action="store_true", help="1000 steps, 3 repeats, N ∈ {1, 64}")
    parser.add_argument("--plants", action="store_true",
                        help="also the MuJoCo plant against the LTI plant on vmc-small-mujoco (see above)")
    parser.add_argument("--json", metavar="FILE", help="write every figure to FILE as JSON")
    args = parser.parse_args(argv)
    if args.quick:
        args.steps, args.repeats, args.envs = 1000, 3, [1, 64]
    if args.vector_ids is None:
        ids = feedrate_ids()
        args.vector_ids = sorted({ids[0], ids[-1]}, key=ids.index)
    result: dict = {"steps": args.steps, "vector_steps": args.vector_steps, "repeats": args.repeats,
                    "single": [], "vector": []}
    print(f"ratios against {PENDULUM_ID} in this process (median of {args.repeats}; wall | CPU time)")
    print(f"{'what':46s} {'steps/s':>11s} {'Pendulum':>10s} {'ratio':>7s} {'CPU ratio':>9s}")

    def show(label: str, r: dict) -> None:
        print(f"{label:46s} {r['wall']:11,.0f} {r['p_wall']:10,.0f} {r['ratio_wall']:6.2f}× "
              f"{r['ratio_cpu']:8.2f}×")

    for family in args.families:
        programs = FAMILIES[family]()
        kwargs = {} if programs is None else {"programs": programs}
        for env_id in feedrate_ids():
            env = gym.make(env_id, **kwargs)
            r = against_pendulum(env, run_single, args.steps, 1, args.repeats)
            env.close()
            show(f"{env_id} [{family}]", r)
            result["single"].append({"env": env_id, "family": family, **r})
        modes = {"auto": [None], "on": [True], "off": [False], "both": [False, True]}[args.parallel]
        for vector_id in args.vector_ids:
            short = vector_id.rsplit("-", 1)[-1]
            for n in args.envs:
                for parallel in modes:
                    # (parallel=None is the env's default rule: not passed, so that older versions run too)
                    venv = make_vector(vector_id, n, kwargs, parallel)
                    steps = max(args.vector_steps, args.steps // n)
                    r = against_pendulum(venv, run_vector, steps, n, args.repeats)
                    threads = bool(getattr(getattr(venv, "batch", None), "parallel", False))
                    venv.close()
                    show(f"{short} vector({n}) {'threads' if threads else 'serial'} [{family}]", r)
                    result["vector"].append({"env": vector_id, "envs": n, "parallel": threads,
                                             "family": family, **r})  # fmt: skip
    if args.plants:
        result["plants"] = compare_plants(args, show)
    result["build_vector_64_s"] = build_time(64)
    print(f"FeedrateVectorEnv(64) construction: {result['build_vector_64_s']:.3f} s (compiled code cached)")
    if args.profile:
        for family in args.families:
            programs = FAMILIES[family]()
            kwargs = {} if programs is None else {"programs": programs}
            print(f"\nprofile [{family}]: Python layers of a {args.profile_env} step, own time per step "
                  "(cProfile)")
            layers = profile_layers(args.profile_env, kwargs, args.steps)
            for name, us in layers[:12]:
                print(f"  {us:7.2f} µs  {name}")
            parts = profile_compiled_parts(kwargs, args.steps)
            print(f"profile [{family}]: the compiled work by part (modular step, µs per step)")
            for name, us in parts.items():
                print(f"  {us:7.2f} µs  {name}")
            result.setdefault("profile", {})[family] = {"layers": layers[:12], "compiled_parts": parts}
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
