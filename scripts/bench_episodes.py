#!/usr/bin/env python3
"""Benchmark whole episodes of the deployable baselines (``constant:x``, ``classical``): compiled against the
Python loop, and ``cnc-gym run`` against ``cnc-gym trace`` of the same program.

Three measurements, in CPU time (user + system), median of ``--repeats``, interleaved:

- **commands**: ``cnc-gym trace PROGRAM`` and ``cnc-gym run PROGRAM --policy classical|constant:1.0
  --json``, each in a fresh process with its bytecode and numba caches warm (as a user runs them, start-up
  included); the ratio of each run to the trace. ``--before DIR`` also times the runs with the package in
  DIR (another checkout: ``git archive <commit> cnc_gym configs | tar -x -C DIR``), run with
  ``PYTHONPATH=DIR``, and checks that both print the same JSON summary;
- **split** of a run, in this process: interpreting the program, building the env, the policy's reset
  (the planner plans), then the episode in the Python loop (:func:`cnc_gym.rollout.play`, forced by
  :func:`cnc_gym.rollout.step_by_step`) and compiled (:func:`cnc_gym.rollout.play_compiled`), which must
  give the same episode;
- **bench** (unless ``--no-bench``): ``cnc-gym bench``'s runner on a split of the default suite
  (``--split``, default test), nominal track, policies ``classical`` and ``constant:1.0``, in this process
  with the Python loop and compiled: CPU time of each, and the records, which must be identical.

Without ``--program`` the program is a generated 20 000-line G01/G02 chain (``scripts/bench_trace.py``'s).

Usage::

    .venv/bin/python scripts/bench_episodes.py                                # generated program
    .venv/bin/python scripts/bench_episodes.py --program part.nc --dialect fanuc --machine vmc-small
    .venv/bin/python scripts/bench_episodes.py --program part.nc --before /tmp/old --json out.json
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

_CLI = "import sys; from cnc_gym.cli import main; sys.argv[0] = 'cnc-gym'; sys.exit(main())"
#: ``cnc-gym run`` exits 3 when the program did not finish (the step budget): still a timed run.
_RUN_OK = (0, 3)
POLICIES = ("classical", "constant:1.0")


def timed_cpu(command: list[str], env: dict[str, str], cwd: Path) -> tuple[float, str]:
    """CPU seconds (user + system) of ``command`` in a fresh process (its own rusage), and its stdout."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        process = subprocess.Popen(command, stdout=out, stderr=err, env=env, cwd=cwd)
        _, status, usage = os.wait4(process.pid, 0)
        code = os.waitstatus_to_exitcode(status)
        process.returncode = code
        out.seek(0)
        err.seek(0)
        if code not in _RUN_OK:
            raise SystemExit(f"{' '.join(command)} failed ({code}): {err.read().decode().strip()}")
        return usage.ru_utime + usage.ru_stime, out.read().decode()


def commands(program: Path, dialect: str, machine: str, repeats: int, before: str | None,
             work: Path) -> dict[str, dict[str, float]]:  # fmt: skip
    """The fresh-process figures (see the module docstring)."""
    cli = [sys.executable, "-c", _CLI]
    cached = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    options = [str(program), "--dialect", dialect, "--machine", machine]
    runs: dict[str, tuple[list[str], dict[str, str]]] = {"cnc-gym trace": ([*cli, "trace", *options], cached)}
    for policy in POLICIES:
        runs[f"cnc-gym run --policy {policy}"] = ([*cli, "run", *options, "--policy", policy, "--json",
                                                   "--no-progress"], cached)  # fmt: skip
    if before:
        old = {**cached, "PYTHONPATH": str(Path(before).resolve())}
        for policy in POLICIES:
            runs[f"cnc-gym run --policy {policy}, --before"] = (
                [*cli, "run", *options, "--policy", policy, "--json", "--no-progress"], old)  # fmt: skip
    outputs: dict[str, str] = {}
    for name, (command, env) in runs.items():  # warm-up: bytecode, numba's cache, the file cache
        outputs[name] = timed_cpu(command, env, work)[1]
    cpu: dict[str, list[float]] = {name: [] for name in runs}
    for _ in range(repeats):
        for name, (command, env) in runs.items():
            cpu[name].append(timed_cpu(command, env, work)[0])
    if before:
        for policy in POLICIES:
            name = f"cnc-gym run --policy {policy}"
            now, then = outputs[name], outputs[f"{name}, --before"]
            if json.loads(now) != json.loads(then):
                raise SystemExit(f"{name}: the summary differs from --before's:\n{now}\n{then}")
    trace = statistics.median(cpu["cnc-gym trace"])
    return {name: {"cpu_s": statistics.median(t), "ratio_to_trace": statistics.median(t) / trace}
            for name, t in cpu.items()}  # fmt: skip


def split(program: Path, dialect: str, machine: str, repeats: int) -> dict[str, dict[str, float]]:
    """CPU seconds of a run's parts in this process, per policy (see the module docstring)."""
    from cnc_gym.machine import load_machine
    from cnc_gym.policies import make_policy
    from cnc_gym.programs import load_program
    from cnc_gym.rollout import compiled_rule, play, play_compiled, policy_env, step_by_step

    out: dict[str, dict[str, float]] = {}
    mach = load_machine(machine)
    start = time.process_time()
    loaded = load_program(program, dialect, mach)
    interpret = time.process_time() - start
    for spec in POLICIES:
        times: dict[str, list[float]] = {"env": [], "reset": [], "python_loop": [], "compiled": []}
        episodes = {}
        for _ in range(repeats):
            for mode in ("python_loop", "compiled"):
                policy = make_policy(spec)
                start = time.process_time()
                env = policy_env(policy, programs=[loaded], dialect=dialect, machine=machine)
                observation, info = env.reset(seed=0)
                middle = time.process_time()
                policy.reset(env)  # (the planner's schedule: planned once, then from its cache)
                ready = time.process_time()
                if mode == "python_loop":
                    with step_by_step():
                        episode = play(env, policy, observation, info)
                else:
                    rule = compiled_rule(env, policy)
                    assert rule is not None, "the baseline did not run compiled"
                    episode = play_compiled(env, rule)
                times[mode].append(time.process_time() - ready)
                times["env"].append(middle - start)
                times["reset"].append(ready - middle)
                episodes[mode] = (episode.info, episode.total_return, episode.steps)
                env.close()
        if episodes["python_loop"] != episodes["compiled"]:
            raise SystemExit(f"{spec}: the compiled episode differs from the Python loop's")
        medians = {k: statistics.median(v) for k, v in times.items()}
        out[spec] = {"interpret_cpu_s": interpret, "env_cpu_s": medians["env"],
                     "first_reset_cpu_s": max(times["reset"]), "steps": episodes["compiled"][2],
                     "python_loop_cpu_s": medians["python_loop"], "compiled_cpu_s": medians["compiled"],
                     "speed_up": medians["python_loop"] / medians["compiled"]}  # fmt: skip
    return out


def bench(split_name: str, repeats: int) -> dict[str, float]:
    """``cnc-gym bench``'s runner, Python loop against compiled (see the module docstring)."""
    from cnc_gym.benchmark.runner import BenchConfig, run_bench, suite_programs
    from cnc_gym.benchmark.suites import DEFAULT_SUITE, load_suite
    from cnc_gym.rollout import step_by_step

    suite = load_suite(DEFAULT_SUITE)
    programs, _ = suite_programs(suite.name, split_name)
    config = BenchConfig(programs=programs, policies=list(POLICIES), machine=suite.machine,
                         dialect=suite.dialect, suite=suite.name, suite_version=suite.version,
                         suite_sha256=suite.sha256)  # fmt: skip
    run_bench(config)  # warm: the bounds' disk cache, the planner's first use, the compiled code
    cpu: dict[str, list[float]] = {"python_loop": [], "compiled": []}
    records = {}
    for _ in range(repeats):
        for mode in cpu:
            start = time.process_time()
            if mode == "python_loop":
                with step_by_step():
                    records[mode] = run_bench(config)
            else:
                records[mode] = run_bench(config)
            cpu[mode].append(time.process_time() - start)
    if records["python_loop"] != records["compiled"]:
        raise SystemExit("bench: the compiled episodes' records differ from the Python loop's")
    loop, compiled = statistics.median(cpu["python_loop"]), statistics.median(cpu["compiled"])
    return {"programs": len(programs), "records": len(records["compiled"]), "python_loop_cpu_s": loop,
            "compiled_cpu_s": compiled, "speed_up": loop / compiled, "records_identical": True}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--program", metavar="FILE", help="the program (default: a generated 20 000-line "
                        "G01/G02 chain)")  # fmt: skip
    parser.add_argument("--dialect", default="gsk25i", help="its dialect (default gsk25i)")
    parser.add_argument("--machine", default="vmc-small", help="machine preset (default vmc-small)")
    parser.add_argument("--repeats", type=int, default=3, help="interleaved repeats (default 3)")
    parser.add_argument("--before", metavar="DIR", help="also time the runs with the cnc_gym package in DIR")
    parser.add_argument("--split", default="test", help="the suite split bench runs (default test)")
    parser.add_argument("--no-bench", action="store_true", help="leave out the bench measurement")
    parser.add_argument("--json", metavar="FILE", help="write every figure to FILE as JSON")
    args = parser.parse_args(argv)

    work = Path(tempfile.mkdtemp(prefix="bench_episodes_"))
    try:
        if args.program:
            program = Path(args.program).resolve()
        else:
            from bench_trace import generate_program

            program = work / "chain.nc"
            program.write_text(generate_program(20_000))
        result: dict = {"program": program.name, "dialect": args.dialect, "machine": args.machine,
                        "repeats": args.repeats}  # fmt: skip
        print(f"{program.name} ({args.dialect}, {args.machine}): CPU s, median of {args.repeats}")
        result["commands"] = commands(program, args.dialect, args.machine, args.repeats, args.before, work)
        print(f"{'command (fresh process)':52s} {'CPU s':>7s} {'/ trace':>8s}")
        for name, m in result["commands"].items():
            print(f"{name:52s} {m['cpu_s']:7.3f} {m['ratio_to_trace']:7.2f}×")
        if args.before:
            print("(the runs print the same JSON summary as --before's)")
        result["split"] = split(program, args.dialect, args.machine, args.repeats)
        print(f"{'run, in this process':20s} {'interpret':>9s} {'env':>6s} {'plan':>6s} {'steps':>7s} "
              f"{'Python loop':>11s} {'compiled':>9s} {'speed-up':>8s}")  # fmt: skip
        for spec, m in result["split"].items():
            print(f"{spec:20s} {m['interpret_cpu_s']:9.3f} {m['env_cpu_s']:6.3f} "
                  f"{m['first_reset_cpu_s']:6.3f} {m['steps']:7d} {m['python_loop_cpu_s']:11.3f} "
                  f"{m['compiled_cpu_s']:9.3f} {m['speed_up']:7.2f}×")  # fmt: skip
        print("(the same episode both ways)")
        if not args.no_bench:
            result["bench"] = b = bench(args.split, args.repeats)
            print(f"bench, {args.split} split ({b['programs']} programs, {', '.join(POLICIES)}; nominal "
                  f"track): Python loop {b['python_loop_cpu_s']:.2f} s, compiled {b['compiled_cpu_s']:.2f} s "
                  f"({b['speed_up']:.2f}×); the {b['records']} records identical")  # fmt: skip
        if args.json:
            Path(args.json).write_text(json.dumps(result, indent=1))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
