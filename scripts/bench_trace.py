#!/usr/bin/env python3
"""Benchmark ``cnc-gym trace`` on a 100 000-line G01/G02 program against LinuxCNC's ``rs274 -g``.

Each command runs in a fresh process (start-up included, as a user runs it), its output written to a
file; the commands are interleaved over ``--repeats`` repeats and the median of each is reported, in
wall time and in CPU time (the child's user + system seconds), with the ratio to the reference; also
the least CPU time of the repeats and its ratio (on a loaded machine the steadier of the two).

- **programs**: ``--lines`` blocks of G01 moves with a G02 arc every ``--arc-every`` blocks (default
  10: one arc in ten; alternately I/J and R arcs), and a 3-line file (one G01, one G02 arc), where
  start-up is nearly all of the time;
- **reference**: ``rs274 -g`` (LinuxCNC's stand-alone interpreter, Debian package ``linuxcnc-uspace``)
  on the same programs, when it is on PATH (the program's ``O1000`` line, which rs274ngc would read as
  an O-word, is left out of its copy); else only cnc-gym's figures are printed;
- ``--before DIR``: also time the ``cnc_gym`` package in DIR (another checkout, e.g. from
  ``git archive``), run with ``PYTHONPATH=DIR``: before/after figures in one run;
- **bytecode**: as in an installed package (pip compiles it at install), the Python commands run with
  their bytecode cache: ``PYTHONDONTWRITEBYTECODE`` is dropped from their environment and each command
  runs once, untimed, before the repeats (without the cache, start-up compiles some fifty modules);
- **floors**: ``python -c pass`` and ``python -c 'import numpy'`` (the interpreter's own start-up, and
  with numpy, which the tool path's arrays need), against the 3-line file's reference: what no Python
  command can go below;
- **split**: where ``cnc-gym trace`` spends its time: start-up (the same command on a one-line program),
  interpretation and JSON Lines writing (each timed in this process, CPU time).

Usage::

    .venv/bin/python scripts/bench_trace.py                        # 100 000 lines, 5 repeats
    .venv/bin/python scripts/bench_trace.py --arc-every 2          # half of the blocks arcs
    .venv/bin/python scripts/bench_trace.py --before /tmp/main-checkout --json out.json
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

STARTUP = "cnc-gym trace, 3-line file"
STARTUP_BEFORE = "cnc-gym trace, 3-line file, --before"
REFERENCE_TINY = "rs274 -g, 3-line file"
#: The floors under any Python command's start-up, timed beside it: the interpreter alone, and with numpy
#: (which the tool path's arrays need); compared with the 3-line file's reference.
FLOORS = {"floor: python -c pass": "pass", "floor: python -c 'import numpy'": "import numpy"}
#: The 3-line file: a move, an arc and the program end.
TINY = "G21 G90 G01 X5 Y0 F1200\nG02 X10 Y5 R5\nM30\n"


def generate_program(n_lines: int, arc_every: int = 10) -> str:
    """``n_lines`` blocks: a header, G01 moves along a zigzag with a G02 quarter arc every ``arc_every``
    blocks (I/J and R forms alternately), then M30."""
    out = ["%", "O1000", "G21 G17 G90 G94 G54", "G00 X0 Y0 Z5", "G01 Z-1 F800"]
    x, y, k, arcs = 0.0, 0.0, 0, 0
    while len(out) < n_lines - 2:
        k += 1
        if k % arc_every == 0:  # clockwise quarter arc of radius 1 from (x, y) to (x + 1, y - 1)
            arcs += 1
            words = "I0 J-1.000" if arcs % 2 else "R1.000"
            x, y = x + 1.0, y - 1.0
            out.append(f"G02 X{x:.3f} Y{y:.3f} {words} F1200")
        else:
            x += 0.5
            y += 0.25 if k % 2 else -0.25
            out.append(f"G01 X{x:.3f} Y{y:.3f} F1200")
    out += ["M30", "%"]
    return "\n".join(out) + "\n"
_TRACE = "import sys; from cnc_gym.cli import main; sys.argv[0] = 'cnc-gym'; sys.exit(main())"


def timed_run(command: list[str], output: Path, env: dict[str, str] | None = None) -> tuple[float, float]:
    """(wall s, CPU s) of ``command`` in a fresh process, its stdout written to ``output``."""
    with output.open("wb") as out:
        wall = time.perf_counter()
        # (run from the output's folder: ``python -c`` puts the working directory first on sys.path)
        process = subprocess.Popen(command, stdout=out, stderr=subprocess.PIPE, env=env, cwd=output.parent)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.perf_counter() - wall
    process.returncode = os.waitstatus_to_exitcode(status)
    if process.returncode != 0:
        stderr = process.stderr.read().decode() if process.stderr else ""
        raise SystemExit(f"{' '.join(command)} failed ({process.returncode}): {stderr.strip()}")
    if process.stderr:
        process.stderr.close()
    return wall, usage.ru_utime + usage.ru_stime


def split(text: str) -> dict[str, float]:
    """CPU seconds of interpreting ``text`` and of writing its JSON Lines, in this process."""
    from cnc_gym.gcode import interpret
    from cnc_gym.toolpath.records import toolpath_jsonl

    interpret("G01 X1 F100\n")  # first-use costs out of the figure
    start = time.process_time()
    toolpath = interpret(text, file="<bench>")
    middle = time.process_time()
    toolpath_jsonl(toolpath)
    return {"interpret_cpu_s": middle - start, "write_cpu_s": time.process_time() - middle,
            "rows": len(toolpath)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=100_000, help="program length (default 100 000)")
    parser.add_argument("--arc-every", type=int, default=10, help="a G02 arc every N blocks (default 10)")
    parser.add_argument("--repeats", type=int, default=5, help="interleaved repeats (default 5)")
    parser.add_argument("--before", metavar="DIR", help="also time the cnc_gym package in DIR")
    parser.add_argument("--json", metavar="FILE", help="write every figure to FILE as JSON")
    args = parser.parse_args(argv)

    work = Path(tempfile.mkdtemp(prefix="bench_trace_"))
    try:
        program = work / "program.nc"
        program.write_text(generate_program(args.lines, args.arc_every))
        tiny = work / "tiny.nc"
        tiny.write_text(TINY)
        trace = [sys.executable, "-c", _TRACE, "trace"]
        cached = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        commands: dict[str, tuple[list[str], dict[str, str] | None]] = {
            "cnc-gym trace": ([*trace, str(program)], cached),
            STARTUP: ([*trace, str(tiny)], cached),
            # (OPENBLAS_NUM_THREADS=1 as `cnc-gym` sets it before numpy loads)
            **{name: ([sys.executable, "-c", code], {**cached, "OPENBLAS_NUM_THREADS": "1"})
               for name, code in FLOORS.items()},
        }
        if args.before:
            before_env = {**cached, "PYTHONPATH": str(Path(args.before).resolve())}
            commands["cnc-gym trace, --before"] = ([*trace, str(program)], before_env)
            commands[STARTUP_BEFORE] = ([*trace, str(tiny)], before_env)
        rs274 = shutil.which("rs274")
        if rs274:
            ngc = work / "program.ngc"
            ngc.write_text(program.read_text().replace("O1000\n", "", 1))
            commands["rs274 -g"] = ([rs274, "-g", str(ngc)], None)
            commands[REFERENCE_TINY] = ([rs274, "-g", str(tiny)], None)
        times: dict[str, dict[str, list[float]]] = {name: {"wall": [], "cpu": []} for name in commands}
        for command, environment in commands.values():  # warm-up: bytecode cache, file cache
            timed_run(command, work / "out.txt", environment)
        for _ in range(args.repeats):
            for name, (command, environment) in commands.items():
                wall, cpu = timed_run(command, work / "out.txt", environment)
                times[name]["wall"].append(wall)
                times[name]["cpu"].append(cpu)
        result: dict = {"lines": args.lines, "arc_every": args.arc_every, "repeats": args.repeats}
        reference = "rs274 -g" if rs274 else None
        print(f"{args.lines:,}-line G01/G02 program (an arc every {args.arc_every} blocks) and a 3-line "
              f"file, fresh processes, median of {args.repeats}")  # fmt: skip
        print(f"{'command':46s} {'wall s':>7s} {'CPU s':>7s} {'min CPU':>7s}"
              + ("   ratio to rs274 (wall | CPU | min CPU)" if reference else ""))  # fmt: skip
        medians = {name: {k: statistics.median(v) for k, v in t.items()} for name, t in times.items()}
        for name, m in medians.items():
            # The least CPU time of the repeats too: on a shared machine the other jobs slow a run down
            # (caches, clock), never speed it up, so the minimum is the steadier figure.
            m["cpu_min"] = min(times[name]["cpu"])
        for name, m in medians.items():
            line = f"{name:46s} {m['wall']:7.3f} {m['cpu']:7.3f} {m['cpu_min']:7.3f}"
            if reference:
                tiny_file = name in (STARTUP, STARTUP_BEFORE, REFERENCE_TINY, *FLOORS)
                ref = medians[REFERENCE_TINY if tiny_file else reference]
                m["ratio_wall"], m["ratio_cpu"] = m["wall"] / ref["wall"], m["cpu"] / ref["cpu"]
                m["ratio_cpu_min"] = m["cpu_min"] / ref["cpu_min"]
                line += f"   {m['ratio_wall']:5.2f}× | {m['ratio_cpu']:5.2f}× | {m['ratio_cpu_min']:5.2f}×"
            print(line)
        if not rs274:
            print("(rs274 not on PATH: install Debian's linuxcnc-uspace for the reference)")
        result["commands"] = medians
        parts = split(program.read_text())
        result["split"] = {"startup_cpu_s": medians[STARTUP]["cpu"], **parts}
        print(f"split of cnc-gym trace (CPU s): start-up {result['split']['startup_cpu_s']:.3f}, "
              f"interpret {parts['interpret_cpu_s']:.3f}, write {parts['write_cpu_s']:.3f} "
              f"({parts['rows']:,} tool-path rows)")
        if args.json:
            Path(args.json).write_text(json.dumps(result, indent=1))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
