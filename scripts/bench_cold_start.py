#!/usr/bin/env python3
"""Benchmark the first ``make demo`` after an install: CPU seconds with numba's cache cold, then warm.

The demo (``scripts/demo.py``) runs in a fresh process with ``NUMBA_CACHE_DIR`` pointed at an empty
folder (cold: numba compiles every kernel the demo uses, as on a fresh clone), then again on the cache
that run filled (warm: what every later run costs). The figure is the child's CPU time (user + system):
on a loaded machine wall time says more about the neighbours than about the code. The difference is
the compile.

- ``--before DIR``: also time the ``cnc_gym`` package and ``scripts/demo.py`` of another checkout (e.g.
  from ``git archive``), interleaved with this one's: before/after figures from one run;
- bytecode: as in an installed package (pip compiles it at install), the runs keep Python's bytecode
  cache (``PYTHONDONTWRITEBYTECODE`` is dropped) and each checkout is imported once before the timed runs.

Usage::

    .venv/bin/python scripts/bench_cold_start.py                      # the whole demo, 1 repeat
    .venv/bin/python scripts/bench_cold_start.py --before /tmp/before --programs circle --repeats 2
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--programs", nargs="+", default=None, help="demo programs (default: all)")
    parser.add_argument("--repeats", type=int, default=1, help="cold + warm pairs per checkout (default 1)")
    parser.add_argument("--before", metavar="DIR", help="also time the checkout in DIR")
    parser.add_argument("--json", metavar="FILE", help="write the figures to FILE as JSON")
    args = parser.parse_args(argv)
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
