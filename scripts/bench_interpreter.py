"""Interpreter speed: lines per second on a generated plain G01/G02 program, against a plain-Python baseline.

    .venv/bin/python scripts/bench_interpreter.py [--lines 100000] [--repeats 5]

The program is a zig-zag of G01 lines with G02 arcs (I/J and R forms alternating) between them: the
typical shape of CAM output. The baseline, run on the same text in the same process, is the least any
Python G-code reader must do: split lines, regex-tokenise each into (letter, number) words and convert
the numbers to float. The report gives the median of the repeats for each, in CPU time and in wall
time, and the ratio.
Goal: >= 100 000 lines/s (must: >= 30 000 lines/s).
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from cnc_gym.gcode import interpret

GOAL_LINES_PER_S = 100_000
FLOOR_LINES_PER_S = 30_000


def generate_program(n_lines: int) -> str:
    """``n_lines`` blocks: a header, then G01 moves and G02 arcs alternating, then M30."""
    out = ["%", "O1000", "G21 G17 G90 G94 G54", "G00 X0 Y0 Z5", "G01 Z-1 F800"]
    x, y = 0.0, 0.0
    step = 0.5
    k = 0
    while len(out) < n_lines - 2:
        k += 1
        if k % 4 == 1:
            y += step
            out.append(f"G01 X{x:.3f} Y{y:.3f} F1200")
        elif k % 4 == 2:
            # Semicircle-free quarter arc via I/J: start (x, y), centre (x, y + r), end (x + r, y + r), CW.
            r = 1.0
            out.append(f"G02 X{x + r:.3f} Y{y + r:.3f} I0 J{r:.3f}")
            x, y = x + r, y + r
        elif k % 4 == 3:
            x += 2.0
            out.append(f"G01 X{x:.3f}")
        else:
            r = 1.0
            out.append(f"G02 X{x + r:.3f} Y{y - r:.3f} R{r:.3f}")
            x, y = x + r, y - r
    out.append("M30")
    out.append("%")
    return "\n".join(out) + "\n"


_WORD = re.compile(r"([A-Z])\s*([+-]?\d*\.?\d+)")


def baseline(text: str) -> int:
    """Minimal tokenise-and-float loop: the floor for any Python reader."""
    words = 0
    for line in text.splitlines():
        for _letter, number in _WORD.findall(line.upper()):
            float(number)
            words += 1
    return words


def median_seconds(fn, repeats: int) -> tuple[float, float]:
    """Median wall-clock and median CPU (process) time of ``repeats`` calls.

    CPU time is what this process itself spent; on a machine shared with other jobs it is the fairer
    figure, because wall time also counts the time the process waited for a core.
    """
    wall, cpu = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return statistics.median(wall), statistics.median(cpu)


def split_seconds(text: str, dialect: str = "gsk25i") -> tuple[float, float]:
    """Best-of-3 CPU seconds of the read phase and of the run (execution and ``build()``), apart."""
    import gc

    from cnc_gym.gcode import get_dialect
    from cnc_gym.gcode.interpreter import Interpreter

    spec = get_dialect(dialect)
    best = (float("inf"), float("inf"))
    for _ in range(3):
        gc.disable()  # as interpret() does
        try:
            c0 = time.process_time()
            program = spec.language.reader(spec, None).read(text, "bench.nc")
            c1 = time.process_time()
            Interpreter(program, spec).run()
            c2 = time.process_time()
        finally:
            gc.enable()
        best = min(best, (c1 - c0, c2 - c1), key=sum)
    return best


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    text = generate_program(args.lines)
    n_lines = text.count("\n")
    toolpath = interpret(text, file="bench.nc")  # warm-up, and a sanity check of the output
    wall, cpu = median_seconds(lambda: interpret(text, file="bench.nc"), args.repeats)
    base_wall, base_cpu = median_seconds(lambda: baseline(text), args.repeats)
    rate = n_lines / cpu
    print(f"program     : {n_lines} lines, {len(toolpath)} segments, {toolpath.total_length:.1f} mm path")
    print(f"              lines/s (CPU time)  lines/s (wall)   median of {args.repeats}")
    print(f"interpreter : {n_lines / cpu:16,.0f}  {n_lines / wall:14,.0f}   {cpu * 1e3:.0f} ms CPU")
    print(f"baseline    : {n_lines / base_cpu:16,.0f}  {n_lines / base_wall:14,.0f}   "
          "(regex tokenise + float)")
    print(f"ratio       : the interpreter takes {cpu / base_cpu:.1f}x the baseline's CPU time "
          f"({wall / base_wall:.1f}x wall)")  # fmt: skip
    verdict = "goal met" if rate >= GOAL_LINES_PER_S else ("floor met" if rate >= FLOOR_LINES_PER_S else
                                                           "BELOW THE FLOOR")  # fmt: skip
    print(f"target      : goal {GOAL_LINES_PER_S:,} lines/s, floor {FLOOR_LINES_PER_S:,} (CPU time): "
          f"{verdict}")
    read_s, run_s = split_seconds(text)
    print(f"split       : read {read_s * 1e3:.0f} ms, execute and build the tool path {run_s * 1e3:.0f} ms "
          "(CPU, best of 3)")
    return 0 if rate >= FLOOR_LINES_PER_S else 1


if __name__ == "__main__":
    raise SystemExit(main())
