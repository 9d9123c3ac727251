"""`make demo`: the built-in program suite under both baselines, as a table and as plots.

    .venv/bin/python scripts/demo.py [--machine vmc-small] [--out out/demo] [--programs star pocket]

For each built-in program it runs the constant override at 100 % and the classical planner through the
env (controller + servo plant), prints cycle time, max/RMS contour error and violations, and writes one
PNG per run (path coloured by feed, contour error along the path) under ``--out``; the plots of one program
share one feed colour scale.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from cnc_gym.errors import CncGymError


def main(argv: list[str] | None = None) -> int:
    from cnc_gym.gcode.dialect import DEFAULT_DIALECT
    from cnc_gym.machine import DEFAULT_MACHINE
    from cnc_gym.programs import program_names
    from cnc_gym.runner import default_plot_name, feed_limits, format_table, plot_run, simulate

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machine", default=DEFAULT_MACHINE)
    parser.add_argument("--dialect", default=DEFAULT_DIALECT)
    parser.add_argument("--programs", nargs="+", default=None, help="default: the built-in suite")
    parser.add_argument("--policies", nargs="+", default=["constant:1.0", "classical"])
    parser.add_argument("--out", default="out/demo", help="folder for the plots")
    args = parser.parse_args(argv)
    programs = args.programs or program_names()
    out = Path(args.out)
    rows, plots = [], []
    started = time.perf_counter()
    try:
        for program in programs:
            results = [simulate(program, dialect=args.dialect, machine=args.machine, policy=policy)
                       for policy in args.policies]  # fmt: skip
            # One feed colour scale for the program's plots, so the policies compare at a glance.
            shared = feed_limits(results)
            for result in results:
                rows.append(result.summary())
                plots.append(plot_run(result, out / default_plot_name(result), feed_range=shared))
    except CncGymError as exc:
        print(f"demo: {exc}", file=sys.stderr)
        return 2
    print(f"cnc-gym demo: {len(programs)} programs x {len(args.policies)} policies on {args.machine} "
          f"({time.perf_counter() - started:.1f} s)\n")  # fmt: skip
    print(format_table(rows))
    print(f"\nplots: {out}/ ({len(plots)} PNG files, one feed colour scale per program)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
