#!/usr/bin/env python3
"""Benchmark the first ``make demo`` after an install: CPU seconds with numba's cache cold, then warm.

The demo (``scripts/demo.py``) runs in a fresh process with ``NUMBA_CACHE_DIR`` pointed at an empty
folder (cold: numba compiles every kernel the demo uses, as on a fresh clone), then again on the cache
that run filled (warm: what every later run costs). The figure is the child's CPU time (user + system):
on a loaded machine wall time says more about the neighbours than about the code. The difference is
the compile.

- ``--before DIR``: also time the ``cnc_gym`` package and ``scripts/demo.py`` of another checkout (e.g.
  from ``git archive``), interleaved with this one's: before/after figures from one run;
- ``--functions``: instead, one cold run of this checkout's demo that records each compile numba does
  (its ``numba:compile`` events) and prints where the time goes, per numba function: how many
  signatures it was compiled for, its own CPU time (the compiles of the functions it calls taken out:
  numba compiles a callee when it types the caller), of which LLVM (optimising and emitting machine
  code: a function's module links in the code of everything it calls and LLVM optimises all of it
  again), and its time with its callees; ``--signatures`` also lists each signature and its caller;
- bytecode: as in an installed package (pip compiles it at install), the runs keep Python's bytecode
  cache (``PYTHONDONTWRITEBYTECODE`` is dropped) and each checkout is imported once before the timed runs.

Usage::

    .venv/bin/python scripts/bench_cold_start.py                      # the whole demo, 1 repeat
    .venv/bin/python scripts/bench_cold_start.py --before /tmp/before --programs circle --repeats 2
    .venv/bin/python scripts/bench_cold_start.py --functions --programs circle   # per-function table
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
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent


def cpu_run(command: list[str], env: dict[str, str]) -> float:
    """CPU seconds (user + system) of ``command`` in a fresh process; its output is discarded."""
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    _, status, usage = os.wait4(process.pid, 0)
    stderr = process.stderr.read().decode() if process.stderr else ""
    if process.stderr:
        process.stderr.close()
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(command)} failed: {stderr.strip()}")
    return usage.ru_utime + usage.ru_stime


def record_compiles(out: Path, demo_args: list[str]) -> None:
    """Run the demo in this process with a listener on numba's compile events; write one row per compile
    (function, signature, CPU seconds with its callees, without them, LLVM's part, and the function whose
    compile asked for it) to ``out``."""
    import runpy
    import time

    from numba.core import event

    stack: list[list] = []  # per compile in progress: [data, CPU at start, callees' CPU, LLVM CPU]
    rows: list[tuple[str, str, float, float, float, str]] = []
    llvm_started: list[float] = []

    class Compiles(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            stack.append([ev.data, time.process_time(), 0.0, 0.0])

        def on_end(self, ev: event.Event) -> None:
            data, started, callees, llvm = stack.pop()
            spent = time.process_time() - started
            if stack:
                stack[-1][2] += spent
            caller = _qualified(stack[-1][0]["dispatcher"].py_func) if stack else ""
            name = _qualified(data["dispatcher"].py_func)
            rows.append((name, str(data["args"]), spent, spent - callees, llvm, caller))

    class Llvm(event.Listener):  # llvmlite holds this lock in each call into LLVM (optimising, emitting code)
        def on_start(self, ev: event.Event) -> None:
            llvm_started.append(time.process_time())

        def on_end(self, ev: event.Event) -> None:
            spent = time.process_time() - llvm_started.pop()
            if stack and not llvm_started:  # (the lock is re-entrant: count the outermost hold)
                stack[-1][3] += spent

    event.register("numba:compile", Compiles())
    event.register("numba:llvm_lock", Llvm())
    started = time.process_time()
    sys.argv = [str(REPO / "scripts" / "demo.py"), *demo_args]
    try:
        runpy.run_path(sys.argv[0], run_name="__main__")
    except SystemExit as exc:
        if exc.code:
            raise
    total = time.process_time() - started
    out.write_text(json.dumps({"total_cpu_s": total, "compiles": rows}))


def _qualified(function: Any) -> str:
    return f"{function.__module__}.{function.__qualname__}"


def function_table(programs: list[str] | None, signatures: bool, top: int) -> dict:
    """One cold demo run in a child process (:func:`record_compiles`): the table of numba's compiles."""
    work = Path(tempfile.mkdtemp(prefix="bench_cold_start_"))
    try:
        demo_args = ["--out", str(work / "plots"), *(["--programs", *programs] if programs else [])]
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(PYTHONPATH=str(REPO), NUMBA_CACHE_DIR=str(work / "numba"))
        out = work / "compiles.json"
        subprocess.run([sys.executable, str(Path(__file__).resolve()), "--record-compiles", str(out), "--",
                        *demo_args], env=env, check=True, stdout=subprocess.DEVNULL)  # fmt: skip
        recorded = json.loads(out.read_text())
    finally:
        shutil.rmtree(work, ignore_errors=True)
    per: dict[str, dict] = {}
    for name, signature, spent, own, llvm, caller in recorded["compiles"]:
        f = per.setdefault(
            name, {"signatures": [], "own_cpu_s": 0.0, "llvm_cpu_s": 0.0, "with_callees_s": 0.0}
        )
        f["signatures"].append(f"{signature}" + (f"  (from {caller})" if caller else ""))
        f["own_cpu_s"] += own
        f["llvm_cpu_s"] += llvm
        f["with_callees_s"] += spent
    compiling = sum(f["own_cpu_s"] for f in per.values())
    programs_text = " ".join(programs) if programs else "all programs"
    print(
        f"scripts/demo.py ({programs_text}), numba's cache cold: {recorded['total_cpu_s']:.1f} s of CPU, "
        f"{compiling:.1f} s compiling ({len(recorded['compiles'])} compiles of {len(per)} functions)"
    )
    print(f"{'own s':>7s} {'LLVM s':>7s} {'+callees':>8s} {'sigs':>4s}  function")
    ranked = sorted(per.items(), key=lambda item: -item[1]["own_cpu_s"])
    for name, f in ranked[:top]:
        print(f"{f['own_cpu_s']:7.2f} {f['llvm_cpu_s']:7.2f} {f['with_callees_s']:8.2f} "
              f"{len(f['signatures']):4d}  {name}")  # fmt: skip
        if signatures:
            for signature in f["signatures"]:
                print(f"{'':34s}{signature[:200]}")
    rest = ranked[top:]
    if rest:
        print(
            f"{sum(f['own_cpu_s'] for _, f in rest):7.2f} {sum(f['llvm_cpu_s'] for _, f in rest):7.2f} "
            f"{'':8s} {sum(len(f['signatures']) for _, f in rest):4d}  ({len(rest)} more functions)"
        )
    return {"total_cpu_s": recorded["total_cpu_s"], "compiling_cpu_s": compiling, "functions": per}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--programs", nargs="+", default=None, help="demo programs (default: all)")
    parser.add_argument("--repeats", type=int, default=1, help="cold + warm pairs per checkout (default 1)")
    parser.add_argument("--before", metavar="DIR", help="also time the checkout in DIR")
    parser.add_argument("--json", metavar="FILE", help="write the figures to FILE as JSON")
    parser.add_argument("--functions", action="store_true",
                        help="one cold run: the compile time of each numba function")  # fmt: skip
    parser.add_argument("--signatures", action="store_true", help="with --functions: list each signature")
    parser.add_argument("--top", type=int, default=25, help="with --functions: rows shown (default 25)")
    parser.add_argument("--record-compiles", metavar="FILE", help=argparse.SUPPRESS)  # (the child's part)
    parser.add_argument("demo_args", nargs="*", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.record_compiles:
        record_compiles(Path(args.record_compiles), args.demo_args)
        return 0
    if args.functions:
        table = function_table(args.programs, args.signatures, args.top)
        if args.json:
            Path(args.json).write_text(json.dumps(table, indent=1))
        return 0
    checkouts = {"this checkout": REPO}
    if args.before:
        checkouts["--before"] = Path(args.before).resolve()
    dropped = ("PYTHONDONTWRITEBYTECODE", "NUMBA_CACHE_DIR")
    base_env = {k: v for k, v in os.environ.items() if k not in dropped}
    work = Path(tempfile.mkdtemp(prefix="bench_cold_start_"))
    times: dict[str, dict[str, list[float]]] = {name: {"cold": [], "warm": []} for name in checkouts}
    try:
        for root in checkouts.values():  # the bytecode cache, out of the figures
            env = {**base_env, "PYTHONPATH": str(root)}
            subprocess.run([sys.executable, "-c", "import cnc_gym.envs, cnc_gym.runner"], env=env,
                           check=True, cwd=work, capture_output=True)  # fmt: skip
        for repeat in range(args.repeats):
            for name, root in checkouts.items():
                cache = work / f"numba-{repeat}-{len(times[name]['cold'])}-{root.name}"
                env = {**base_env, "PYTHONPATH": str(root), "NUMBA_CACHE_DIR": str(cache)}
                command = [sys.executable, str(root / "scripts" / "demo.py"), "--out", str(work / "plots")]
                if args.programs:
                    command += ["--programs", *args.programs]
                times[name]["cold"].append(cpu_run(command, env))
                times[name]["warm"].append(cpu_run(command, env))
                shutil.rmtree(cache, ignore_errors=True)
                print(f"{name}: cold {times[name]['cold'][-1]:.1f} s, warm {times[name]['warm'][-1]:.1f} s "
                      "CPU", file=sys.stderr, flush=True)  # fmt: skip
    finally:
        shutil.rmtree(work, ignore_errors=True)
    programs = " ".join(args.programs) if args.programs else "all programs"
    print(f"scripts/demo.py ({programs}), fresh processes, CPU s (user + system), median of {args.repeats}")
    print(f"{'checkout':16s} {'cold':>7s} {'warm':>7s} {'compile':>8s}")
    result: dict = {"programs": args.programs, "repeats": args.repeats, "checkouts": {}}
    for name, t in times.items():
        cold, warm = statistics.median(t["cold"]), statistics.median(t["warm"])
        result["checkouts"][name] = {"cold_cpu_s": cold, "warm_cpu_s": warm, "runs": t}
        print(f"{name:16s} {cold:7.1f} {warm:7.1f} {cold - warm:8.1f}")
    if args.before:
        this, before = result["checkouts"]["this checkout"], result["checkouts"]["--before"]
        print(f"cold start, this checkout / --before: {this['cold_cpu_s'] / before['cold_cpu_s']:.2f}×")
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
