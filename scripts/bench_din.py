"""DIN interpreter speed (the ``azmc1`` dialect): lines/s on a plain G01 program and blocks/s on a
``$WHILE`` loop program, each beside a plain-Python reference run on the same text in the same process.

    .venv/bin/python scripts/bench_din.py [--lines 100000] [--passes 50000] [--repeats 5]

* **G01 program**: ``--lines`` blocks ``N… G01 X… Y… F…`` of a zig-zag (CAM-like output, block numbers,
  blanks between words), read and executed. References: the least any Python reader must do — split lines,
  regex-tokenise each into (letter, number) words and convert the numbers to float — and the Fanuc-family
  interpreter (``gsk25i``) on the same blocks.
* **$WHILE program**: a loop of ``--passes`` passes, four blocks each (the test, an assignment with an
  expression, an assignment sharing its block with a move, ``$ENDWHILE``). Blocks/s counts every block
  executed. Reference: the same loop written in Python (a ``while`` over a list of parameters, the same
  arithmetic, a tuple per move) — what the loop costs with no interpreter at all.

Medians of ``--repeats`` runs, CPU time (the fairer figure on a shared machine) and wall time.
Goals (issue 16): >= 100 000 lines/s on the G01 program, >= 200 000 blocks/s on the $WHILE program.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_interpreter import baseline as tokenise
from bench_interpreter import median_seconds, split_seconds

from cnc_gym.gcode import interpret

GOAL_LINES_PER_S = 100_000
GOAL_BLOCKS_PER_S = 200_000
BLOCKS_PER_PASS = 4


def g01_program(n_lines: int) -> str:
    """``n_lines`` blocks: a header, G01 moves of a zig-zag, M30."""
    out = ["%100 (bench)", "N1 G00 X0 Y0 Z5", "N2 G01 Z-1 F800"]
    x = 0.0
    y = 0.0
    n = 2
    while len(out) < n_lines - 1:
        n += 1
        if n % 2:
            x = 100.0 - x
        y += 0.05
        out.append(f"N{n % 10000} G01 X{x:.4f} Y{y:.4f} F1200")
    out.append("M30")
    return "\n".join(out) + "\n"


def while_program(passes: int) -> str:
    """A ``$WHILE`` loop of ``passes`` passes, :data:`BLOCKS_PER_PASS` blocks a pass."""
    return (f"%200 (bench)\nR1 = {passes}\nR2 = 0\nG01 F1000\n$WHILE R1 > 0.5\n"
            "R2 = R2 + 0.01 + 0.001 * SIN[R1]\nR1 = R1 - 1 X R2\n$ENDWHILE\nM30\n")


def python_loop(passes: int) -> int:
    """The $WHILE program's loop in plain Python (the same arithmetic, one tuple per move)."""
    import math

    r = [0.0] * 10
    r[1] = float(passes)
    moves = []
    while r[1] > 0.5:
        r[2] = r[2] + 0.01 + 0.001 * math.sin(math.radians(r[1]))
        r[1] = r[1] - 1
        moves.append((r[2], 0.0, 0.0))
    return len(moves)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=100_000)
    parser.add_argument("--passes", type=int, default=50_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)

    text = g01_program(args.lines)
    n_lines = text.count("\n")
    toolpath = interpret(text, dialect="azmc1", file="bench.din")  # warm-up and sanity check
    wall, cpu = median_seconds(lambda: interpret(text, dialect="azmc1", file="bench.din"), args.repeats)
    base_wall, base_cpu = median_seconds(lambda: tokenise(text), args.repeats)
    fanuc_text = text.replace("%100 (bench)", "%")  # the same blocks, a Fanuc tape start
    gsk_wall, gsk_cpu = median_seconds(lambda: interpret(fanuc_text, file="bench.nc"), args.repeats)
    line_rate = n_lines / cpu
    print(f"G01 program   : {n_lines} lines, {len(toolpath)} segments")
    print(f"                lines/s (CPU)   lines/s (wall)   median of {args.repeats}")
    print(f"  interpreter : {line_rate:13,.0f}  {n_lines / wall:15,.0f}   {cpu * 1e3:.0f} ms CPU")
    print(f"  reference   : {n_lines / base_cpu:13,.0f}  {n_lines / base_wall:15,.0f}   (tokenise + float)")
    print(f"  gsk25i      : {n_lines / gsk_cpu:13,.0f}  {n_lines / gsk_wall:15,.0f}   (the Fanuc family)")
    print(f"  ratio       : the interpreter takes {cpu / base_cpu:.1f}x the tokeniser's CPU time, "
          f"{cpu / gsk_cpu:.2f}x the gsk25i interpreter's")
    read_s, run_s = split_seconds(text, "azmc1")
    print(f"  split       : read {read_s * 1e3:.0f} ms, execute and build the tool path {run_s * 1e3:.0f} ms "
          "(CPU, best of 3)")

    loop = while_program(args.passes)
    toolpath = interpret(loop, dialect="azmc1", file="loop.din")
    assert len(toolpath) == args.passes, len(toolpath)
    blocks = args.passes * BLOCKS_PER_PASS + 1  # the last, failing test too
    wall, cpu = median_seconds(lambda: interpret(loop, dialect="azmc1", file="loop.din"), args.repeats)
    base_wall, base_cpu = median_seconds(lambda: python_loop(args.passes), args.repeats)
    block_rate = blocks / cpu
    print(f"$WHILE program: {args.passes} passes, {blocks} blocks executed, {len(toolpath)} segments")
    print("                blocks/s (CPU)  blocks/s (wall)")
    print(f"  interpreter : {block_rate:13,.0f}  {blocks / wall:15,.0f}   {cpu * 1e3:.0f} ms CPU")
    print(f"  reference   : {blocks / base_cpu:13,.0f}  {blocks / base_wall:15,.0f}   (plain Python)")
    print(f"  ratio       : the interpreter takes {cpu / base_cpu:.1f}x the reference's CPU time")
    ok = line_rate >= GOAL_LINES_PER_S and block_rate >= GOAL_BLOCKS_PER_S
    print(f"goals         : {GOAL_LINES_PER_S:,} lines/s, {GOAL_BLOCKS_PER_S:,} blocks/s (CPU time): "
          f"{'met' if ok else 'NOT MET'}")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
