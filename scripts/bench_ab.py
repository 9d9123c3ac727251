"""Interpreter speed of two checkouts side by side: the same programs, alternating runs, CPU time.

    .venv/bin/python scripts/bench_ab.py BASE_CHECKOUT [--other CHECKOUT] [--runs 8] [--repeats 3]

BASE_CHECKOUT is another checkout of this repository (for example ``git worktree add /tmp/base df1fc99``);
``--other`` defaults to this one. The programs are those of ``scripts/bench_interpreter.py`` (a 100 000-line
G01/G02 program) and ``scripts/bench_macros.py`` (the WHILE spiral and the G65 calls, 20 000 moves each),
generated once here and given to both checkouts. Each run is a fresh process that imports ``cnc_gym`` from
one checkout and times ``interpret`` ``--repeats`` times; the runs alternate between the checkouts so that
both see the same load. On a shared machine the spread between runs is large (another job takes a core),
so the report gives the minimum CPU time (the least disturbed run) beside the median, and their ratios.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from tqdm import tqdm

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_interpreter  # noqa: E402
import bench_macros  # noqa: E402

#: Run in a fresh process: import cnc_gym from the checkout given, time interpret() on the program file.
TIMER = """
import json, sys, time
sys.path.insert(0, sys.argv[1])
from cnc_gym.gcode import interpret
text = open(sys.argv[2], encoding="ascii").read()
interpret(text, file="bench.nc")
times = []
for _ in range(int(sys.argv[3])):
    start = time.process_time()
    interpret(text, file="bench.nc")
    times.append(time.process_time() - start)
print(json.dumps(min(times)))
"""


def programs() -> dict[str, str]:
    """The benchmark programs, by name."""
    return {
        "plain": bench_interpreter.generate_program(100_000),
        "loop": bench_macros.loop_program(20_000)[0],
        "calls": bench_macros.calls_program(20_000)[0],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("base", type=Path, help="the other checkout (the reference)")
    parser.add_argument("--other", type=Path, default=HERE.parent,
                        help="the checkout compared (default: this one)")
    parser.add_argument("--runs", type=int, default=8, help="alternating runs per checkout and program")
    parser.add_argument("--repeats", type=int, default=3,
                        help="interpret() calls per run (its minimum counts)")
    args = parser.parse_args(argv)
    checkouts = {"base": args.base.resolve(), "other": args.other.resolve()}
    for name, path in checkouts.items():
        if not (path / "cnc_gym" / "gcode" / "__init__.py").is_file():
            parser.error(f"{name} checkout {path} has no cnc_gym/gcode package")
    results: dict[tuple[str, str], list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        files = {}
        for name, text in programs().items():
            files[name] = Path(tmp) / f"{name}.nc"
            files[name].write_text(text, encoding="ascii")
        jobs = [(program, which) for _ in range(args.runs) for program in files for which in checkouts]
        for program, which in tqdm(jobs, desc="runs", unit="run"):
            out = subprocess.run([sys.executable, "-c", TIMER, str(checkouts[which]), str(files[program]),
                                  str(args.repeats)], capture_output=True, text=True, check=True)  # fmt: skip
            results.setdefault((program, which), []).append(json.loads(out.stdout))
    print(f"base : {checkouts['base']}\nother: {checkouts['other']}")
    print(f"{'program':8} {'base min':>9} {'other min':>9} {'ratio':>6}   {'base med':>9} {'other med':>9} "
          f"{'ratio':>6}   (CPU s per interpret)")  # fmt: skip
    for program in files:
        base, other = results[(program, "base")], results[(program, "other")]
        lo = (min(base), min(other))
        med = (statistics.median(base), statistics.median(other))
        print(f"{program:8} {lo[0]:9.3f} {lo[1]:9.3f} {lo[1] / lo[0]:6.3f}   {med[0]:9.3f} {med[1]:9.3f} "
              f"{med[1] / med[0]:6.3f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
