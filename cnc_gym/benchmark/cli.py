"""``cnc-gym bench``: benchmark policies on a suite split or on your own programs.

    cnc-gym bench [--suite NAME | --programs FILE ...] [--split train|val|test] [--policy P ...]
                  [--per-family N] [--seeds 0,1,2] [--track nominal|perturbed|mujoco]
                  [--machine M] [--plant lti|mujoco] [--dialect D] [--units mm|inch]
                  [--setup FILE] [--calculator-input] [--max-time SECONDS] [--max-cpu SECONDS]
                  [--workers N] [--ray [ADDRESS]]
                  [--json OUT.jsonl] [--plot DIR] [--no-progress]

``--json`` gets each record as its episode finishes; Ctrl-C stops the run at once (exit status 130),
keeping every finished record in the file.

:func:`register` adds the subcommand to the ``cnc-gym`` parser; everything else is imported when the
command runs.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

EPILOG = """policies: constant:<x>, classical (deployable planner), oracle (simulate-and-correct, an oracle),
nominal-oracle (the oracle simulating the nominal machine, run on the track's plant),
bound (the time-optimal reference, no episode), a trained model (.zip), or module:callable.
Default: the default suite's test split with constant:1.0, classical, oracle and bound.
Score: 100 x the mean over programs of bound/cycle for finished episodes with no path cut over
tolerance, 0 otherwise (docs/benchmark.md)."""


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``bench`` to the ``cnc-gym`` subcommands."""
    from cnc_gym.defaults import INPUT_UNITS
    from cnc_gym.gcode.dialect import DEFAULT_DIALECT

    bench = subparsers.add_parser("bench", help="benchmark policies on a suite split or your own programs",
                                  epilog=EPILOG,
                                  formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    source = bench.add_mutually_exclusive_group()
    source.add_argument("--suite", default=None, help="suite name (default: cnc-bench-v1)")
    source.add_argument("--programs", nargs="+", metavar="FILE", help="benchmark these program files instead")
    bench.add_argument("--split", default=None, choices=("train", "val", "test"), help="default: test")
    bench.add_argument("--policy", action="append", default=None, metavar="P",
                       help="a policy to run (repeatable); see below")  # fmt: skip
    bench.add_argument("--per-family", type=int, default=None, metavar="N",
                       help="at most N programs of each family of the split (a quick look)")  # fmt: skip
    bench.add_argument("--seeds", default="0", help="comma-separated episode seeds (default 0)")
    bench.add_argument("--machine", default=None, help="machine preset or YAML (default: the suite's)")
    bench.add_argument("--track", default="nominal", choices=("nominal", "perturbed", "mujoco"),
                       help="the plant the episodes run on: the nominal machine (default), its MuJoCo plant, "
                            "or that plant with parameters drawn per program (docs/benchmark.md, Tracks)")
    bench.add_argument("--plant", metavar="lti|mujoco", default=None,
                       help="servo plant for the episodes on the nominal track (default: the machine "
                            "preset's)")
    bench.add_argument("--dialect", default=None,
                       help=f"program dialect (default: the suite's, {DEFAULT_DIALECT})")  # fmt: skip
    bench.add_argument("--units", choices=INPUT_UNITS, default=None,
                       help="input unit at power-on for programs without G20/G21 (default: the machine "
                            "preset's power_on_units, else the dialect's G21)")  # fmt: skip
    bench.add_argument("--setup", metavar="FILE", default=None,
                       help="the operator's work and tool offsets (YAML, docs/configs.md), on top of the "
                            "machine preset's setup section")  # fmt: skip
    bench.add_argument("--calculator-input", action="store_true",
                       help="calculator-type input: a number without a decimal point is in mm/inch/s "
                            "(Fanuc parameter 3401#0 DPI = 1)")  # fmt: skip
    bench.add_argument("--max-time", type=float, default=None, metavar="SECONDS",
                       help="stop each episode after this much simulated time (it counts as not finished; "
                            "its record says stopped_by: max_time)")  # fmt: skip
    bench.add_argument("--max-cpu", type=float, default=None, metavar="SECONDS",
                       help="stop each episode after this much CPU time, the policy's planning included "
                            "(stopped_by: max_cpu; such a record depends on the machine)")  # fmt: skip
    bench.add_argument("--workers", type=int, default=1, metavar="N",
                       help="local worker processes (default 1)")  # fmt: skip
    bench.add_argument("--ray", nargs="?", const="", default=None, metavar="ADDRESS",
                       help="run episodes on Ray (a local instance, or the cluster at ADDRESS); "
                            "needs pip install 'cnc-gym[ray]'")  # fmt: skip
    bench.add_argument("--json", metavar="OUT.jsonl",
                       help="write one JSON record per episode, each as its episode finishes")  # fmt: skip
    bench.add_argument("--plot", metavar="DIR", help="write pareto.png and families.png into DIR")
    bench.add_argument("--no-progress", action="store_true", help="no progress bar")
    bench.set_defaults(func=cmd_bench)
    return bench


def _seeds(text: str) -> list[int]:
    from cnc_gym.errors import CncGymError

    try:
        seeds = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise CncGymError(f"--seeds must be integers separated by commas, got {text!r}") from None
    if not seeds or any(s < 0 for s in seeds) or len(set(seeds)) != len(seeds):
        raise CncGymError(f"--seeds must be distinct non-negative integers, got {text!r}")
    return seeds


def cmd_bench(args: argparse.Namespace) -> int:
    import time

    from cnc_gym.benchmark.metrics import format_table, summarize
    from cnc_gym.benchmark.runner import (
        DEFAULT_POLICIES,
        BenchConfig,
        EpisodeLimits,
        JsonlAppender,
        run_bench,
        suite_programs,
        user_programs,
    )
    from cnc_gym.benchmark.suites import DEFAULT_SUITE
    from cnc_gym.errors import CncGymError
    from cnc_gym.gcode.dialect import DEFAULT_DIALECT
    from cnc_gym.machine import DEFAULT_MACHINE, machine_with_options
    from cnc_gym.rollout import announce_compiling

    if args.plant is not None and args.track != "nominal":
        raise CncGymError(f"--plant sets the nominal track's plant; the {args.track} track has its own")
    if args.workers < 1:
        raise CncGymError(f"--workers must be at least 1, got {args.workers}")
    seeds = _seeds(args.seeds)
    limits = EpisodeLimits(max_time_s=args.max_time, max_cpu_s=args.max_cpu)
    policies = [p.strip() for p in (args.policy or DEFAULT_POLICIES)]
    if len(set(policies)) != len(policies):
        raise CncGymError("each --policy may be given once")
    if args.programs:
        if args.per_family is not None:
            raise CncGymError("--per-family picks programs of a suite's split; with --programs, name the "
                              "files to run")  # fmt: skip
        machine, dialect = args.machine or DEFAULT_MACHINE, args.dialect or DEFAULT_DIALECT
        if args.setup is not None or args.calculator_input:  # they travel inside the machine record
            machine = machine_with_options(machine, args.setup, args.calculator_input)
        programs = user_programs(args.programs, machine, dialect, args.units)
        config = BenchConfig(programs=programs, policies=policies, seeds=seeds, machine=machine,
                             dialect=dialect, units=args.units)  # fmt: skip
        title = f"{len(programs)} program(s)"
    else:
        name = args.suite or DEFAULT_SUITE
        split = args.split or "test"
        programs, suite = suite_programs(name, split)
        if args.per_family is not None:
            if args.per_family < 1:
                raise CncGymError(f"--per-family must be at least 1, got {args.per_family}")
            kept, counts = [], dict.fromkeys((p.family for p in programs), 0)
            for program in programs:
                if counts[program.family] < args.per_family:
                    counts[program.family] += 1
                    kept.append(program)
            programs = kept
        config = BenchConfig(programs=programs, policies=policies, seeds=seeds,
                             machine=args.machine or suite.machine, dialect=args.dialect or suite.dialect,
                             units=args.units,
                             suite=suite.name, suite_version=suite.version,
                             suite_sha256=suite.sha256)  # fmt: skip
        title = f"{suite.name} {split}"
        if args.setup is not None or args.calculator_input:
            config.machine = machine_with_options(config.machine, args.setup, args.calculator_input)
    config.workers = args.workers
    config.plant = args.plant
    config.track = args.track
    config.limits = limits
    if args.ray is not None:
        config.use_ray, config.ray_address = True, args.ray or None
    config.progress = not args.no_progress and sys.stderr.isatty()
    # The file is made before any work (an unwritable path costs nothing) and gets each record as its
    # task finishes: Ctrl-C keeps every finished one.
    out = JsonlAppender(args.json) if args.json else None
    announce_compiling(sys.stderr)
    started = time.perf_counter()
    try:
        records = run_bench(config, on_records=out.append if out is not None else None)
    except KeyboardInterrupt:
        if out is not None:
            out.close()
            saved = f"kept {out.count} finished episode record(s) in {out.path}"
        else:
            saved = "no --json, so no records kept"
        print(f"cnc-gym bench: interrupted after {time.perf_counter() - started:.1f} s; {saved}",
              file=sys.stderr)  # fmt: skip
        return 130
    except BaseException:
        if out is not None:
            out.close()
        raise
    elapsed = time.perf_counter() - started
    if out is not None:
        out.finish(records)
    if args.plot:
        from cnc_gym.benchmark.plots import write_plots

        write_plots(records, args.plot, title=title)
    ran = len({r["program"] for r in records})
    left_out = len(config.programs) - ran
    machine_name = records[0]["machine"] if records else config.machine
    counted = f"{ran} programs" + (f" ({left_out} left out)" if left_out else "")
    print(f"{title}: {counted}, track {config.track}, machine {machine_name}, "
          f"seeds {','.join(map(str, seeds))}, "
          f"commit {records[0]['commit'] if records else '?'}")  # fmt: skip
    print(format_table(summarize(records)), flush=True)
    cut = sum(1 for r in records if r.get("stopped_by") in ("max_time", "max_cpu"))
    note = f" ({cut} cut by --max-time/--max-cpu)" if cut else ""
    print(f"{len(records)} episodes in {elapsed:.1f} s{note}", file=sys.stderr)
    return 0
