"""The ``cnc-gym`` command.

    cnc-gym trace PROGRAM [--dialect D] [--machine M] [--units mm|inch] [--setup FILE] [--calculator-input]
                          [--block-skip N ...] [--program-dir DIR] [--follow-links] [--max-blocks N]
    cnc-gym run PROGRAM [--dialect D] [--machine M] [--units mm|inch] [--setup FILE] [--calculator-input]
                        [--plant lti|mujoco] [--policy P] [--json] [--plot FILE.png|DIR/] [--max-time SECONDS]
                        [--max-blocks N] [--no-progress]
    cnc-gym bench [--suite NAME | --programs FILE ...] [--split S] [--policy P ...] [--workers N] ...

PROGRAM is a G-code file or a built-in program name (``circle``, ``star``, ``freeform``, ``pocket``), by
the rule of :mod:`cnc_gym.programs`. ``trace`` prints the canonical tool path as JSON Lines (``kind``,
``line``, ``end``, ``feed``, ``center``, ``plane``, ``sweep_deg``, ``seconds`` and extras). ``--units``
sets the input unit at power-on (:data:`UNITS_HELP`), ``--setup`` the operator's work and tool offsets
(:data:`SETUP_HELP`). ``run``
simulates the program through controller and plant (implemented in :mod:`cnc_gym.runner`). ``bench``
benchmarks policies on a suite or your programs (:mod:`cnc_gym.benchmark.cli`).

Exit status: 0 success; 2 an error a user can cause, as one line on stderr (for a program:
``FILE:LINE: message [code]``), with nothing on stdout and never a traceback; 3 (``run``) the run stopped
before the program's end (step budget or ``--max-time``): the results are printed with ``finished:
false`` and a line on stderr says why; 130 interrupted.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Sequence
from typing import NoReturn

# Before numpy loads (the imports below): the commands' linear algebra is on small matrices (3-vectors, the
# servo models' 5×5), where OpenBLAS's thread pool only costs. Started with a thread per core, it spins at
# load: 0.1 s of CPU, a third of `cnc-gym trace`'s start on two cores (scripts/bench_trace.py). A value the
# user set wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from cnc_gym.defaults import DEFAULT_MACHINE, INPUT_UNITS
from cnc_gym.errors import MAX_LINE_CHARS, CncGymError, printable
from cnc_gym.gcode.dialect import DEFAULT_DIALECT, DIALECT_MODULES
from cnc_gym.gcode.settings import DEFAULT_MAX_BLOCKS
from cnc_gym.programs import BUILTIN_PROGRAMS

EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
DIALECTS = tuple(DIALECT_MODULES)


EXIT_STATUS_HELP = """exit status:
  0    success
  2    bad program, arguments, machine, policy or model: one line on stderr, nothing on stdout
  3    (run) truncated: the run stopped before the program's end (step budget or --max-time);
       the results are printed (finished: false) and a line on stderr says why
  130  interrupted (Ctrl-C)"""

UNITS_HELP = ("input unit at power-on, mm or inch (a controller parameter: a program without G20/G21 "
              "is read in it; the program's own G20/G21 still rules). Default: the machine preset's "
              "power_on_units, else the dialect's power-on code (G21)")
SETUP_HELP = ("the operator's tables at power-on (YAML: work_offsets G54.. -> [x, y, z], tools n -> "
              "length_mm, radius_mm; docs/configs.md), on top of the machine preset's setup section; the "
              "program's G10 still changes them")
CALCULATOR_HELP = ("calculator-type input (Fanuc parameter 3401#0 DPI = 1): a number without a decimal "
                   "point is in mm/inch/s, X10 = 10 mm (default: the machine preset's calculator_input, "
                   "else the dialect's reading: fanuc X10 = 0.01 mm)")
PROGRAM_HELP = (f"G-code file, or a built-in program name: {', '.join(BUILTIN_PROGRAMS)} (a built-in name "
                "wins over a file of that name in the current folder: write ./star for the file)")


class CommandParser(argparse.ArgumentParser):
    """argparse's parser, with a usage error in two lines: a one-line usage and the error (argparse's
    own usage of ``bench`` wraps over eight lines). ``--help`` still prints the whole usage."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.short_usage()}\n{_one_line(f'{self.prog}: error: {message}')}\n")

    def short_usage(self) -> str:
        """``usage: cnc-gym run PROGRAM [options] (cnc-gym run --help)``: the positionals, then a hint."""
        words = [self.prog]
        for action in self._actions:
            if action.option_strings:
                continue
            name = action.metavar or action.dest.upper()
            words.append(f"{name} ..." if isinstance(action, argparse._SubParsersAction) else str(name))
        return f"usage: {' '.join(words)} [options] (all of them: {self.prog} --help)"


def build_parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="cnc-gym", description="CNC feed-rate control gym: tools.",
                                     epilog=EXIT_STATUS_HELP,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    trace = add_command(sub, "trace", "print the canonical tool path of a program as JSON Lines")
    trace.add_argument("program", metavar="PROGRAM", help=PROGRAM_HELP)
    _common(trace)
    trace.add_argument("--block-skip", metavar="N", type=int, nargs="+", action="extend", default=[],
                       help="block skip switches that are ON (1..9; '/' alone is switch 1)")  # fmt: skip
    trace.add_argument("--program-dir", metavar="DIR", default=None,
                       help="where M98/G65 find called programs (default: the program's folder)")  # fmt: skip
    trace.add_argument("--follow-links", action="store_true",
                       help="let a called program's file be a link out of that folder (refused by default)")
    trace.set_defaults(func=cmd_trace)

    run = add_command(sub, "run", "simulate a program through controller and servo plant")
    run.add_argument("program", metavar="PROGRAM", help=PROGRAM_HELP)
    _common(run)
    run.add_argument("--plant", metavar="lti|mujoco", default=None,
                     help="servo plant: lti (exact linear model) or mujoco (masses, friction, backlash); "
                          "default: the machine preset's")  # fmt: skip
    run.add_argument("--policy", default="constant:1.0",
                     help="constant:<override>, classical (deployable), oracle (re-simulates the plant: "
                          "an oracle, not deployable), a trained model's path (.zip), or module:callable "
                          "(default constant:1.0)")
    run.add_argument("--json", action="store_true", help="print one JSON object with the results")
    run.add_argument("--plot", metavar="FILE.png|DIR/",
                     help="save a plot of path, contour error and feed (.png, .pdf or .svg; a folder gets "
                          "PROGRAM_POLICY.png)")  # fmt: skip
    run.add_argument("--max-time", metavar="SECONDS", type=float, default=None,
                     help="stop after this much simulated time (the run then counts as truncated, exit 3)")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.set_defaults(func=cmd_run)

    from cnc_gym.benchmark.cli import register as register_bench  # all bench code: cnc_gym/benchmark/

    register_bench(sub)
    return parser


def add_command(sub: argparse._SubParsersAction, name: str, help_text: str) -> argparse.ArgumentParser:
    """A subcommand whose help ends with the exit statuses."""
    return sub.add_parser(name, help=help_text, description=help_text, epilog=EXIT_STATUS_HELP,
                          formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--dialect", default=DEFAULT_DIALECT,
                        help=f"controller dialect: {', '.join(DIALECTS)}")  # fmt: skip
    parser.add_argument("--machine", default=None,
                        help="machine preset name (configs/machines) or YAML path; default: none for trace, "
                             f"{DEFAULT_MACHINE} for run")  # fmt: skip
    parser.add_argument("--units", choices=INPUT_UNITS, default=None, help=UNITS_HELP)
    parser.add_argument("--setup", metavar="FILE", default=None, help=SETUP_HELP)
    parser.add_argument("--calculator-input", action="store_true", help=CALCULATOR_HELP)
    parser.add_argument("--max-blocks", metavar="N", type=int, default=None,
                        help=f"bound on executed blocks; a runaway loop ends in too-many-blocks "
                             f"(default {DEFAULT_MAX_BLOCKS:,})")  # fmt: skip


def _check_arguments(args: argparse.Namespace) -> None:
    """Empty option values are errors, the same for every command (never a silent fallback). Other values
    are checked where they are used (``--max-time`` by the runner, names by their loaders)."""
    for option in ("dialect", "machine", "policy"):
        value = getattr(args, option, None)
        if isinstance(value, str) and not value.strip():
            raise CncGymError(f"cnc-gym {args.command}: --{option} needs a value, got {value!r}")
    max_blocks = getattr(args, "max_blocks", None)
    if max_blocks is not None and max_blocks < 1:
        raise CncGymError(f"cnc-gym {args.command}: --max-blocks must be a positive integer, "
                          f"got {max_blocks}")  # fmt: skip


def cmd_trace(args: argparse.Namespace) -> int:
    from cnc_gym.gcode import interpret, interpret_file
    from cnc_gym.programs import resolve_program

    machine = None
    if args.machine is not None:
        from cnc_gym.machine import load_machine

        machine = load_machine(args.machine)
    options = {"dialect": args.dialect, "machine": machine, "block_skip": frozenset(args.block_skip),
               "program_dir": args.program_dir, "units": args.units, "setup": args.setup,
               "calculator_input": args.calculator_input or None,
               "follow_links": args.follow_links}  # fmt: skip
    if args.max_blocks is not None:
        options["max_blocks"] = args.max_blocks
    source = resolve_program(args.program)
    if source.path is None:  # text
        toolpath = interpret(source.text or "", file=f"<{source.name}>", **options)
    else:
        toolpath = interpret_file(source.path, **options)
    # The whole program is interpreted before anything is printed: an error leaves stdout empty.
    from cnc_gym.toolpath.records import toolpath_jsonl

    text = toolpath_jsonl(toolpath)
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. `cnc-gym trace p.nc | head`: not an error
        _silence_stdout()
    print_notices(toolpath.notices)
    return 0


def print_notices(notices: Sequence[str]) -> None:
    """The interpreter's notes about a program, one line each on stderr (the tool path is on stdout)."""
    for line in notices:
        print(_one_line(line), file=sys.stderr)


def cmd_run(args: argparse.Namespace) -> int:
    if args.setup is not None or args.calculator_input:  # both travel inside the machine record
        from cnc_gym.machine import machine_with_options

        machine = args.machine or DEFAULT_MACHINE
        args.machine = machine_with_options(machine, args.setup, args.calculator_input)
    try:
        from cnc_gym.runner import run_cli

        return int(run_cli(args) or 0)
    except ImportError as exc:
        # A part of the simulation stack that is missing (not yet built or not installed): one line.
        print(f"cnc-gym run: the simulation runner is not available ({exc})", file=sys.stderr)
        return EXIT_USAGE


def _silence_stdout() -> None:
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``cnc-gym`` console script. Returns the exit status.

    Run as the program (``argv`` None), an interrupted command (status 130) ends the process at once:
    by then its files are closed and its workers ended, and the interpreter's teardown of the numeric
    libraries (numba, toppra, torch) would add 1–2 s on a loaded machine before Ctrl-C takes effect."""
    parser = build_parser()
    args, unknown = parser.parse_known_args(list(argv) if argv is not None else None)
    if unknown:  # said by the command's parser, with its usage (argparse leaves it to the top one)
        _command_parser(parser, args.command).error(f"unrecognized arguments: {' '.join(unknown)}")
    status = EXIT_USAGE
    try:
        _check_arguments(args)
        status = args.func(args)
    except CncGymError as exc:
        print_notices(getattr(exc, "notices", ()))
        print(_one_line(str(exc)), file=sys.stderr)
    except OSError as exc:
        program = getattr(args, "program", "")
        where = exc.filename if exc.filename is not None else program
        verb = "cannot read: " if where == program else ""
        print(_one_line(f"{where}: {verb}{exc.strerror or exc}"), file=sys.stderr)
    except KeyboardInterrupt:
        print("cnc-gym: interrupted", file=sys.stderr)
        status = EXIT_INTERRUPTED
    if status == EXIT_INTERRUPTED and argv is None:
        _exit_now(status)
    return status


def _command_parser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction) and command in action.choices:
            return action.choices[command]
    return parser


def _exit_now(status: int) -> None:
    """Flush the output and end the process without the interpreter's teardown (a local Ray instance is
    shut down first: it would outlive the process otherwise; multiprocessing releases a pool's locks, or
    its resource tracker would warn about them)."""
    ray = sys.modules.get("ray")
    if ray is not None and getattr(ray, "is_initialized", lambda: False)():
        ray.shutdown()
    if "multiprocessing" in sys.modules:  # what its exit hook does: release a pool's queues and locks
        from multiprocessing import util

        with contextlib.suppress(Exception):
            util._exit_function()  # type: ignore[attr-defined]
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):
            stream.flush()
    os._exit(status)


def _one_line(message: str) -> str:
    return printable(message, MAX_LINE_CHARS) or "error"


if __name__ == "__main__":
    raise SystemExit(main())
