"""The ``cnc-gym`` command.

    cnc-gym trace PROGRAM [--dialect D] [--machine M] [--block-skip N ...] [--program-dir DIR]
    cnc-gym run PROGRAM [--dialect D] [--machine M] [--policy P] [--json] [--plot FILE.png] [--no-progress]

``trace`` prints the canonical tool path as JSON Lines (the contract in DESIGN.md: ``kind``, ``line``,
``end``, ``feed``, ``center``, ``plane``, ``sweep_deg``, ``seconds`` and extras). ``run`` simulates the
program through controller and plant (implemented in :mod:`cnc_gym.runner`).

Every error a user can cause ends the command with exit status 2 and one line on stderr (for a program:
``FILE:LINE: message [code]``); nothing is printed on stdout once an error has occurred, and never a
traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from cnc_gym.errors import MAX_LINE_CHARS, CncGymError, printable

EXIT_USAGE = 2
DIALECTS = ("gsk25i", "h4cm", "syntec", "azmc1")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="cnc-gym", description="CNC feed-rate control gym: tools.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    trace = sub.add_parser("trace", help="print the canonical tool path of a program as JSON Lines")
    trace.add_argument("program", metavar="PROGRAM", help="G-code program file")
    _common(trace)
    trace.add_argument("--block-skip", metavar="N", type=int, nargs="+", action="extend", default=[],
                       help="block skip switches that are ON (1..9; '/' alone is switch 1)")  # fmt: skip
    trace.add_argument("--program-dir", metavar="DIR", default=None,
                       help="where M98/G65 find called programs (default: the program's folder)")  # fmt: skip
    trace.set_defaults(func=cmd_trace)

    run = sub.add_parser("run", help="simulate a program through controller and servo plant")
    run.add_argument("program", metavar="PROGRAM", help="G-code program file")
    _common(run)
    run.add_argument("--policy", default="constant:1.0",
                     help="constant:<override>, classical, or a trained model's path (default constant:1.0)")
    run.add_argument("--json", action="store_true", help="print one JSON object with the results")
    run.add_argument("--plot", metavar="FILE.png", help="save a plot of path, contour error and feed")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.set_defaults(func=cmd_run)
    return parser


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--dialect", default="gsk25i", help=f"controller dialect: {', '.join(DIALECTS)}")
    parser.add_argument("--machine", default=None,
                        help="machine preset name (configs/machines) or YAML path; default: none for trace, "
                             "the runner's default for run")  # fmt: skip


def cmd_trace(args: argparse.Namespace) -> int:
    from cnc_gym.gcode import interpret_file

    machine = None
    if args.machine is not None:
        from cnc_gym.machine import load_machine

        machine = load_machine(args.machine)
    toolpath = interpret_file(args.program, dialect=args.dialect, machine=machine,
                              block_skip=frozenset(args.block_skip),
                              program_dir=args.program_dir)  # fmt: skip
    # The whole program is interpreted before anything is printed: an error leaves stdout empty.
    text = "".join(json.dumps(record) + "\n" for record in toolpath.to_records())
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. `cnc-gym trace p.nc | head`: not an error
        _silence_stdout()
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    try:
        from cnc_gym.runner import run_cli

        return int(run_cli(args) or 0)
    except ImportError as exc:
        # A part of the simulation stack that is missing (not yet built or not installed): one line.
        print(f"cnc-gym run: the simulation runner is not available ({exc})", file=sys.stderr)
        return EXIT_USAGE


def _silence_stdout() -> None:
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``cnc-gym`` console script. Returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(list(argv) if argv is not None else None)
    try:
        return args.func(args)
    except CncGymError as exc:
        print(_one_line(str(exc)), file=sys.stderr)
    except OSError as exc:
        where = exc.filename if exc.filename is not None else getattr(args, "program", "")
        print(f"{where}: cannot read: {exc.strerror or exc}", file=sys.stderr)
    except KeyboardInterrupt:
        print("cnc-gym: interrupted", file=sys.stderr)
        return 130
    return EXIT_USAGE


def _one_line(message: str) -> str:
    return printable(message, MAX_LINE_CHARS) or "error"


if __name__ == "__main__":
    raise SystemExit(main())
