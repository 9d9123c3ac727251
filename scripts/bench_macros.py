"""Macro interpreter speed: executed blocks per second on macro-heavy programs, against plain Python.

    .venv/bin/python scripts/bench_macros.py [--moves 20000] [--repeats 5]

Two programs, each generating ``--moves`` feed moves from a handful of source lines:

* ``loop``  — one WHILE loop: per pass a condition, three assignments with trigonometry, a G01 with
  variable words and an END (6 blocks per move): a spiral.
* ``calls`` — a G65 macro called once per row of 10 moves; inside, a WHILE loop of 10 moves (per row:
  the call, the macro's 3 set-up blocks, 10 x 5 loop blocks, the final test, M99).

Executed blocks are counted from the program's structure (the formula is checked once against the
interpreter's own ``max_blocks`` bound: one block less must fail). The baseline does the same arithmetic
and list appends in a plain Python loop (what any Python macro evaluator costs at least). The report gives
the median of the repeats, in CPU time and wall time.
Goal: >= 20 000 blocks/s (CPU time).
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret

GOAL_BLOCKS_PER_S = 20_000


def loop_program(moves: int) -> tuple[str, int]:
    """A spiral from one WHILE loop; returns (text, executed blocks)."""
    text = f"""O1000
G90 G17 G21 F1500
#1=0
WHILE[#1LT{moves}]DO1
#2=#1*0.01+5
#3=#2*COS[#1*3.6]
#4=#2*SIN[#1*3.6]
G01 X#3 Y#4
#1=#1+1
END1
M30
"""
    # O, G90 line, #1=0 → 3; each pass: WHILE, #2, #3, #4, G01, #1, END → 7; final WHILE → 1; M30 → 1.
    return text, 3 + 7 * moves + 1 + 1


def calls_program(moves: int) -> tuple[str, int]:
    """Rows of 10 moves, one G65 call per row; returns (text, executed blocks)."""
    rows = max(1, moves // 10)
    text = f"""O2000
G90 F2000
#100=0
WHILE[#100LT{rows}]DO1
G65 P2001 A#100 B10
#100=#100+1
END1
M30
O2001
#5=0
#6=#1*2
G01 Y#6
WHILE[#5LT#2]DO1
#5=#5+1
#7=[#5+#1]*3+SIN[#5*9]
G01 X#7
END1
M99
"""
    # Main: O, G90, #100=0 → 3; per row: WHILE, G65, #100, END → 4; final WHILE, M30 → 2.
    # Per call: the O2001 block (a call enters at its O block), #5, #6, G01 Y → 4;
    # per move: WHILE, #5, #7, G01, END → 5; final WHILE, M99 → 2.
    return text, 3 + rows * (4 + 4 + 5 * 10 + 2) + 2


def baseline_loop(moves: int) -> int:
    """The spiral's arithmetic in plain Python: what any Python macro evaluator costs at least."""
    variables: dict[int, float] = {1: 0.0}
    path = []
    while variables[1] < moves:
        variables[2] = variables[1] * 0.01 + 5
        variables[3] = variables[2] * math.cos(math.radians(variables[1] * 3.6))
        variables[4] = variables[2] * math.sin(math.radians(variables[1] * 3.6))
        path.append((variables[3], variables[4], 0.0))
        variables[1] = variables[1] + 1
    return len(path)


def median_seconds(fn, repeats: int) -> tuple[float, float]:
    """Median wall-clock and median CPU (process) time of ``repeats`` calls."""
    wall, cpu = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return statistics.median(wall), statistics.median(cpu)


def check_block_count(make) -> None:
    """The executed-block formula against the interpreter's own bound, on a small instance."""
    text, blocks = make(50)
    interpret(text, max_blocks=blocks)
    try:
        interpret(text, max_blocks=blocks - 1)
    except ProgramError as err:
        assert err.code == "too-many-blocks", err
    else:
        raise AssertionError(f"{make.__name__}: fewer blocks than the formula's {blocks}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    print(f"              blocks/s (CPU)  blocks/s (wall)  moves/s (CPU)   median of {args.repeats}")
    worst = math.inf
    for name, make in (("loop", loop_program), ("calls", calls_program)):
        check_block_count(make)
        text, blocks = make(args.moves)
        toolpath = interpret(text, file=f"{name}.nc")  # warm-up and sanity check
        wall, cpu = median_seconds(lambda text=text: interpret(text, file="bench.nc"), args.repeats)
        worst = min(worst, blocks / cpu)
        print(f"{name:12s}: {blocks / cpu:14,.0f}  {blocks / wall:15,.0f}  {len(toolpath) / cpu:13,.0f}   "
              f"{blocks} blocks, {len(toolpath)} moves, {cpu * 1e3:.0f} ms CPU")
    base_wall, base_cpu = median_seconds(lambda: baseline_loop(args.moves), args.repeats)
    text, blocks = loop_program(args.moves)
    print(f"{'baseline':12s}: {blocks / base_cpu:14,.0f}  {blocks / base_wall:15,.0f}  "
          f"{args.moves / base_cpu:13,.0f}   plain Python doing the spiral's arithmetic ('loop' block count)")
    verdict = "goal met" if worst >= GOAL_BLOCKS_PER_S else "BELOW THE GOAL"
    print(f"target      : {GOAL_BLOCKS_PER_S:,} blocks/s (CPU time), slowest program {worst:,.0f}: {verdict}")
    return 0 if worst >= GOAL_BLOCKS_PER_S else 1


if __name__ == "__main__":
    raise SystemExit(main())
