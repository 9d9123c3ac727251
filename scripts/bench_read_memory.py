"""Memory per line of a plain G01 program: the read phase, and the whole interpretation.

    .venv/bin/python scripts/bench_read_memory.py --lines 200000
    .venv/bin/python scripts/bench_read_memory.py --lines 1000000 --rss

A generated program of ``--lines`` plain G01 lines (``G01 X12.345 Y-6.789 Z0.5 F1200``, coordinates varied
so that few words repeat) is read (``read_program``) and interpreted (``interpret``) in this process under
``tracemalloc``: the peak of traced memory above the text itself, divided by the lines, is the memory per
line of each phase. ``--rss`` runs each phase again in a fresh child process and reports its peak resident
set (``ru_maxrss``) above the child's baseline (the interpreter imported, the text built), which also
counts what tracemalloc does not see (numpy's buffers are traced; the allocator's slack is not).

The interpreter's documented goal (docs/gcode.md, "Bounds on time and memory"): at most 300 bytes per
line of such a program in the read phase, so that the block and segment budgets, not ``MemoryError``,
stop a huge one.
"""

from __future__ import annotations

import argparse
import gc
import json
import multiprocessing
import resource
import sys
import tracemalloc


def program(lines: int) -> str:
    """``lines`` plain G01 lines with varied coordinates (about 30 bytes each)."""
    out = ["G90 G01 F1200"]
    for n in range(lines - 1):
        x = (n * 7919) % 200000 / 1000 - 100
        y = (n * 104729) % 150000 / 1000 - 75
        out.append(f"G01 X{x:.3f} Y{y:.3f} Z{(n % 50) / 10:.1f}")
    return "\n".join(out) + "\n"


def _phase(text: str, phase: str, dialect: str = "gsk25i") -> None:
    from cnc_gym.gcode import interpret, read_program

    if phase == "read":
        result = read_program(text, dialect=dialect)
        assert len(result.blocks) > 0
    else:
        # tracemalloc slows the run several times: no CPU-time bound here
        result = interpret(text, dialect=dialect, max_segments=max(2_000_000, text.count("\n") + 1),
                           max_seconds=1e6)  # fmt: skip
        assert len(result) > 0
    del result


def traced(text: str, phase: str, dialect: str = "gsk25i") -> int:
    """Peak traced bytes of one phase above what was allocated before it."""
    gc.collect()
    tracemalloc.start()
    base = tracemalloc.get_traced_memory()[0]
    try:
        _phase(text, phase, dialect)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return peak - base


def _status(key: str) -> int | None:
    """A size from /proc/self/status (``VmRSS``, ``VmHWM``) in bytes, None where there is none."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def _child(conn, lines: int, phase: str, dialect: str) -> None:
    import cnc_gym.gcode  # noqa: F401 - imported before the baseline

    text = program(lines)
    gc.collect()
    try:  # reset the peak RSS (Linux): a spawned child inherits its parent's high-water mark across exec
        with open("/proc/self/clear_refs", "w") as refs:
            refs.write("5")
        base, peak = _status("VmRSS"), "VmHWM"
    except OSError:
        base, peak = None, ""
    if base is None:
        base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    _phase(text, phase, dialect)
    top = _status(peak) if peak else None
    conn.send((top if top is not None else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024) - base)


def rss(lines: int, phase: str, dialect: str = "gsk25i") -> int:
    """Peak resident-set growth of one phase in a fresh process."""
    context = multiprocessing.get_context("spawn")
    parent, child = context.Pipe()
    process = context.Process(target=_child, args=(child, lines, phase, dialect))
    process.start()
    value = parent.recv()
    process.join()
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lines", type=int, default=200_000, help="lines of the program (200000)")
    parser.add_argument("--rss", action="store_true", help="also measure the peak RSS in a fresh process")
    parser.add_argument("--dialect", default="gsk25i", help="dialect to read the program in (gsk25i)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    result: dict = {"lines": args.lines, "dialect": args.dialect, "python": sys.version.split()[0]}
    if args.rss:  # first, while this process is small (a child starts from a copy of it)
        for phase in ("read", "interpret"):
            grown = rss(args.lines, phase, args.dialect)
            result[f"{phase}_rss_bytes_per_line"] = round(grown / args.lines, 1)
    text = program(args.lines)
    result["text_bytes"] = len(text.encode())
    for phase in ("read", "interpret"):
        result[f"{phase}_traced_bytes_per_line"] = round(traced(text, phase, args.dialect) / args.lines, 1)
    if args.json:
        print(json.dumps(result))
    else:
        print(f"program ({args.dialect}): {args.lines} lines, {result['text_bytes'] / 2**20:.1f} MiB of text "
              f"({result['text_bytes'] / args.lines:.1f} bytes/line)")  # fmt: skip
        for phase in ("read", "interpret"):
            line = f"{phase:<10} traced peak {result[f'{phase}_traced_bytes_per_line']:8.1f} bytes/line"
            if args.rss:
                line += f", peak RSS growth {result[f'{phase}_rss_bytes_per_line']:8.1f} bytes/line"
            print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
