#!/usr/bin/env python3
"""Peak memory of a process holding one env: the peak resident set of a fresh child, phase by phase.

A child process imports numpy, numba, Gymnasium and cnc_gym, then the env's module (the one its entry
point names), runs ``gymnasium.make(id)``, one reset and ``--steps`` steps with random actions (resetting
at episode ends), and reports its peak resident set (``VmHWM`` on Linux) after each phase, and at the end how
much of what is resident is file-backed (shared libraries' pages, which processes running the same
libraries share) and how much anonymous (the process's own). References run the same way:

- ``numba floor``: numpy, numba, Gymnasium, then one call of a trivial function loaded from numba's disk
  cache: what any process that runs numba-compiled code from the cache pays before an env of its own (numba
  compiles its runtime and imports ``scipy.linalg`` for its BLAS the first time it readies its target);
- the env again, with that call before ``import cnc_gym``: its later phases are then the env's own;
- ``Pendulum-v1``: numpy, Gymnasium, make, steps.

Each figure is the median over ``--repeats`` children. One child of each runs first and is not counted,
so that numba's disk cache and the planner's servo table are on disk (the warm case: what every process
after the first pays). The child also lists which of the heavy modules of ``NOTED`` it ended up loading.

On Linux the peak is the child's ``VmHWM`` (``/proc/self/status``), which counts only the child's own
program: its ``ru_maxrss`` would start at the launching process's resident set (the peak carries over
``exec``).

Usage::

    .venv/bin/python scripts/bench_env_memory.py                  # the newest env id, 3 children each
    .venv/bin/python scripts/bench_env_memory.py --id cnc_gym/Feedrate-v0 --steps 500 --json mem.json
"""

from __future__ import annotations

# Only what the child needs at module level: the parent's imports (argparse, json, subprocess, ...) would
# otherwise sit in every child's figures.
import resource
import sys
from typing import Any

PENDULUM_ID = "Pendulum-v1"
NUMBA_FLOOR = "numba floor"
#: Heavy modules whose presence after a make and steps is worth seeing (scipy: numba imports
#: ``scipy.linalg`` itself; yaml: the machine presets are YAML files).
NOTED = ("scipy", "yaml", "matplotlib", "pydantic", "toppra", "mujoco", "torch", "tqdm", "rich")


def peak_mib() -> float:
    """This process's peak resident set so far, MiB: ``VmHWM`` on Linux (the high-water mark of this
    program's memory, which starts afresh at ``exec``), else ``ru_maxrss`` (bytes on macOS). On Linux
    ``ru_maxrss`` would carry the launching process's resident set over ``exec``: under a large parent
    (a test runner) every phase would read as the parent's size."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 2**10
    except OSError:
        pass
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 2**10


def resident_split() -> dict[str, float]:
    """The current resident set's file-backed and anonymous parts, MiB (Linux; empty elsewhere)."""
    split = {}
    try:
        with open("/proc/self/status") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key in ("RssFile", "RssAnon"):
                    split[key] = int(value.split()[0]) / 2**10
    except OSError:
        pass
    return split


def _trivial_sum(x: Any) -> float:
    """The numba floor's function (compiled with ``cache=True`` in the child)."""
    total = 0.0
    for value in x:
        total += value
    return total


def child(env_id: str, steps: int, floor_first: bool = False) -> dict[str, Any]:
    """Run the phases in this (fresh) process; the peak after each, in order. ``floor_first``: call the
    numba floor's function before importing cnc_gym, so that the later phases are the env's own."""
    phases: list[tuple[str, float]] = [("python", peak_mib())]
    import importlib

    import numpy as np

    phases.append(("import numpy", peak_mib()))
    if env_id != PENDULUM_ID:
        import numba

        phases.append(("import numba", peak_mib()))
    import gymnasium as gym

    phases.append(("import gymnasium", peak_mib()))
    if env_id == NUMBA_FLOOR or floor_first:
        numba.njit(cache=True)(_trivial_sum)(np.ones(3))
        phases.append(("one function from numba's cache", peak_mib()))
        if env_id == NUMBA_FLOOR:
            return _figures(phases, resident_split())
    if env_id != PENDULUM_ID:
        import cnc_gym  # noqa: F401  (registers the ids)

        phases.append(("import cnc_gym", peak_mib()))
    entry_point = gym.spec(env_id).entry_point
    if isinstance(entry_point, str):
        importlib.import_module(entry_point.split(":")[0])
        phases.append(("import the env's module", peak_mib()))
    env = gym.make(env_id)
    phases.append(("gymnasium.make", peak_mib()))
    env.reset(seed=0)
    env.action_space.seed(0)
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
    phases.append((f"reset + {steps} steps", peak_mib()))
    end = resident_split()
    env.close()
    return _figures(phases, end)


def _figures(phases: list[tuple[str, float]], end: dict[str, float]) -> dict[str, Any]:
    return {"phases": phases, "end": end, "loaded": [m for m in NOTED if m in sys.modules]}


def child_main(env_id: str, steps: int, floor_first: bool = False) -> None:
    figures = child(env_id, steps, floor_first)
    import json  # after the phases: not in their figures

    print(json.dumps(figures))


def run_child(env_id: str, steps: int, floor_first: bool = False) -> dict[str, Any]:
    import json
    import subprocess
    from pathlib import Path

    # Imported, not run as a script: a script's source is compiled in the child, a module's bytecode is
    # read from its cache, as in a user's process.
    code = (
        f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); import bench_env_memory; "
        f"bench_env_memory.child_main({env_id!r}, {steps}, {floor_first})"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    result: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
    return result


def measure(env_id: str, steps: int, repeats: int, floor_first: bool = False) -> dict[str, Any]:
    """The median peak after each phase over ``repeats`` fresh children (after one uncounted warm-up)."""
    import statistics

    run_child(env_id, steps, floor_first)  # warms numba's disk cache and the servo table; not counted
    runs = [run_child(env_id, steps, floor_first) for _ in range(repeats)]
    names = [name for name, _ in runs[0]["phases"]]
    medians = [statistics.median(run["phases"][i][1] for run in runs) for i in range(len(names))]
    end = {key: statistics.median(run["end"][key] for run in runs) for key in runs[0]["end"]}
    phases = dict(zip(names, medians, strict=True))
    name = f"{env_id}, numba's floor first" if floor_first else env_id
    return {"id": name, "steps": steps, "repeats": repeats, "phases": phases, "peak_mib": medians[-1],
            "end": end, "loaded": runs[0]["loaded"]}  # fmt: skip


def table(results: list[dict[str, Any]]) -> str:
    lines = []
    for result in results:
        lines.append(f"{result['id']}: peak resident set (MiB) after each phase, "
                     f"median of {result['repeats']} fresh processes")  # fmt: skip
        before = 0.0
        for name, peak in result["phases"].items():
            lines.append(f"  {name:34s} {peak:7.1f}   {peak - before:+7.1f}")
            before = peak
        if result["end"]:
            lines.append(f"  resident at the end: {result['end']['RssFile']:.1f} file-backed, "
                         f"{result['end']['RssAnon']:.1f} anonymous")  # fmt: skip
        lines.append(f"  of {', '.join(NOTED)} loaded: {', '.join(result['loaded']) or 'none'}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    import argparse
    import json

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--id", default=None, help="env id (default: the newest cnc_gym/Feedrate-* id)")
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-references", action="store_true",
                        help="only the env (no floor first, no numba floor, no Pendulum-v1)")  # fmt: skip
    parser.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    args = parser.parse_args(argv)
    if args.id is None:
        import cnc_gym  # cheap: loads neither Gymnasium nor numba

        args.id = cnc_gym.ENV_IDS[-1]
    runs = [(args.id, False)]
    if not args.no_references:
        runs += [(args.id, True), (NUMBA_FLOOR, False), (PENDULUM_ID, False)]
    results = [measure(env_id, args.steps, args.repeats, floor_first) for env_id, floor_first in runs]
    print(table(results))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
