#!/usr/bin/env python3
"""Run the commands README.md shows and check the output it shows (or rewrite it from the real output).

    .venv/bin/python scripts/readme_tour.py             # check the quick commands (seconds)
    .venv/bin/python scripts/readme_tour.py --slow      # also `make demo` and training (minutes)
    .venv/bin/python scripts/readme_tour.py --update    # rewrite the shown output from the real output

A README command is a line starting with ``$ `` in a fenced code block; the lines after it, up to the next
command or the end of the block, are its shown output (stdout then stderr). A line ``...`` stands for any
number of lines, so a long output can be shown in part. Floats printed at full precision (10 or more
significant digits) are compared to a relative 1e-9: their last bits differ across CPUs, since numba
compiles for the host. ``# exit status N`` at the end of a command is
the status it must end with (0 otherwise). Commands run from the repository root with bash; the Python
blocks run in a fresh interpreter. ``make test`` is not run (it is what runs this check).
``tests/test_readme.py`` runs the quick check on every ``make test`` and the slow one under
``pytest -m slow``.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
#: The start of the line ``cnc-gym run`` and the demo print before numba compiles (cnc_gym.rollout).
COMPILING_PREFIX = "cnc-gym: compiling the simulator"

ELLIPSIS = "..."
#: Commands that take minutes: run only with --slow.
SLOW = ("make demo", "scripts/train.py", "scripts/evaluate.py")
#: Commands never run here: `make test` runs this very check.
NOT_RUN = ("make test",)
_STATUS = re.compile(r"#\s*exit status (\d+)\s*$")
# Lines that vary from run to run: wall-clock times in the demo's first line, install chatter.
_VOLATILE = re.compile(r"\(\d+(\.\d+)? s\)$")


@dataclass
class Command:
    """One ``$`` line of the README and the output shown under it."""

    line: int  # 1-based line of the command in README.md
    text: str  # the command as printed (after "$ ")
    shown: list[str] = field(default_factory=list)
    status: int = 0

    @property
    def slow(self) -> bool:
        return any(key in self.text for key in SLOW)

    @property
    def run_here(self) -> bool:
        return not any(self.text.strip().startswith(key) for key in NOT_RUN)


@dataclass
class Block:
    """One fenced code block: its language and its lines (1-based first line)."""

    language: str
    first_line: int
    lines: list[str]


def blocks(text: str) -> list[Block]:
    """The fenced code blocks of a Markdown text."""
    out, current = [], None
    for number, line in enumerate(text.splitlines(), 1):
        if line.startswith("```"):
            if current is None:
                current = Block(line[3:].strip(), number + 1, [])
            else:
                out.append(current)
                current = None
        elif current is not None:
            current.lines.append(line)
    return out


def commands(text: str) -> list[Command]:
    """The ``$`` commands of the README's shell blocks, each with its shown output."""
    out: list[Command] = []
    for block in blocks(text):
        if block.language not in ("", "console", "shell", "sh"):
            continue
        for offset, line in enumerate(block.lines):
            if line.startswith("$ "):
                match = _STATUS.search(line)
                out.append(Command(block.first_line + offset, line[2:].strip(),
                                   status=int(match.group(1)) if match else 0))  # fmt: skip
            elif out and out[-1].line >= block.first_line:
                out[-1].shown.append(line)
    return out


def unmarked_commands(text: str) -> list[str]:
    """Lines of shell blocks that look like a command but are neither a ``$`` command nor the output of
    one (they would never be run)."""
    starts = (".venv/", "make ", "python", "cnc-gym ")
    found = []
    for block in blocks(text):
        if block.language in ("", "console", "shell", "sh"):
            for line in block.lines:
                if line.startswith("$ "):
                    break  # from here on, every line is a command or the output of one
                if line.startswith(starts):
                    found.append(line)
    return found


def python_blocks(text: str) -> list[Block]:
    return [block for block in blocks(text) if block.language == "python"]


def run(command: Command, timeout: float | None = None) -> tuple[int, list[str]]:
    """Run a command from the repository root; returns its exit status and output lines."""
    env = {**os.environ, "COLUMNS": "200", "TERM": "dumb"}
    proc = subprocess.run(["bash", "-c", command.text], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=timeout)  # fmt: skip
    # README shows what a command prints once numba's cache is warm: the first run's notice (stderr, before
    # the results) depends on which command compiled first, so it is left out of the comparison.
    lines = (proc.stdout + proc.stderr).splitlines()
    return proc.returncode, [line for line in lines if not line.startswith(COMPILING_PREFIX)]


def matches(shown: list[str], actual: list[str]) -> bool:
    """Whether ``actual`` fits ``shown``: literal lines in order, ``...`` for any number of lines.

    Lines are compared by :func:`line_matches`: text exactly, long floats to a relative 1e-9."""
    shown = [_clean(line) for line in shown]
    actual = [_clean(line) for line in actual]
    # fits[i][j]: shown[i:] fits actual[j:] (a small dynamic programme; "..." takes any run of lines).
    fits = [[False] * (len(actual) + 1) for _ in range(len(shown) + 1)]
    fits[len(shown)][len(actual)] = True
    for i in range(len(shown) - 1, -1, -1):
        for j in range(len(actual), -1, -1):
            if shown[i].strip() == ELLIPSIS:
                fits[i][j] = fits[i + 1][j] or (j < len(actual) and fits[i][j + 1])
            else:
                fits[i][j] = j < len(actual) and fits[i + 1][j + 1] and line_matches(shown[i], actual[j])
    return fits[0][0]


#: A float printed with this many significant digits or more is a simulation result at full precision;
#: its last bits differ across CPUs (numba compiles for the host), so it is compared to a relative 1e-9.
_LONG_FLOAT_DIGITS = 10
_LONG_FLOAT_RTOL = 1e-9
_NUMBER = re.compile(r"-?\d+\.\d+(?:[eE][-+]?\d+)?")


def line_matches(shown: str, actual: str) -> bool:
    """One shown line against one printed line: the same text, except that two long floats (at least
    :data:`_LONG_FLOAT_DIGITS` significant digits) in the same place may differ by a relative 1e-9."""
    if shown == actual:
        return True
    shown_parts, actual_parts = _NUMBER.split(shown), _NUMBER.split(actual)
    if shown_parts != actual_parts:
        return False
    for a, b in zip(_NUMBER.findall(shown), _NUMBER.findall(actual), strict=True):
        if a == b:
            continue
        if min(_significant_digits(a), _significant_digits(b)) < _LONG_FLOAT_DIGITS:
            return False
        x, y = float(a), float(b)
        if abs(x - y) > _LONG_FLOAT_RTOL * max(abs(x), abs(y)):
            return False
    return True


def _significant_digits(number: str) -> int:
    mantissa = re.split(r"[eE]", number)[0].lstrip("-").replace(".", "")
    return len(mantissa.lstrip("0"))


def _clean(line: str) -> str:
    return _VOLATILE.sub("(… s)", line.rstrip())


def check(text: str, *, slow: bool) -> list[str]:
    """Problems found (an empty list when every command runs as printed and prints what is shown)."""
    problems = [f"README: a command without '$ ' is never checked: {line}"
                for line in unmarked_commands(text)]  # fmt: skip
    for command in commands(text):
        if not command.run_here or (command.slow and not slow):
            continue
        status, actual = run(command)
        if status != command.status:
            tail = "\n    ".join(actual[-5:])
            problems.append(f"README.md:{command.line}: `{command.text}` exited {status}, expected "
                            f"{command.status}:\n    {tail}")  # fmt: skip
        elif command.shown and not matches(command.shown, actual):
            problems.append(f"README.md:{command.line}: `{command.text}` printed\n    "
                            + "\n    ".join(actual[:20]) + "\n  not what README shows")  # fmt: skip
    for block in python_blocks(text):
        proc = subprocess.run([sys.executable, "-c", "\n".join(block.lines)], cwd=ROOT, capture_output=True,
                              text=True)  # fmt: skip
        if proc.returncode != 0:
            problems.append(f"README.md:{block.first_line}: the Python block fails:\n{proc.stderr[-800:]}")
    return problems


def update(text: str, *, slow: bool) -> str:
    """README text with each run command's shown output replaced by its real output; a shown output that
    starts or ends with ``...`` keeps it and as many literal lines as before."""
    lines = text.splitlines()
    for command in reversed(commands(text)):
        if not command.run_here or (command.slow and not slow) or not command.shown:
            continue
        _, actual = run(command)
        new = _excerpt(command.shown, [line.rstrip() for line in actual])
        start = command.line  # index of the first shown line (0-based: the line after the command)
        lines[start : start + len(command.shown)] = new
    return "\n".join(lines) + "\n"


def _excerpt(shown: list[str], actual: list[str]) -> list[str]:
    """Keep the shape of the shown output: a leading ``...`` keeps the tail, a trailing one the head."""
    literal = [line for line in shown if line.strip() != ELLIPSIS]
    head = shown[0].strip() == ELLIPSIS
    tail = shown[-1].strip() == ELLIPSIS
    if head and tail:
        return shown  # a middle excerpt: leave it to the author
    if tail:
        return [*actual[: len(literal)], ELLIPSIS]
    if head:
        return [ELLIPSIS, *actual[-len(literal) :]]
    return actual


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slow", action="store_true", help="also run make demo and the training commands")
    parser.add_argument("--update", action="store_true", help="rewrite README.md's shown output")
    args = parser.parse_args(argv)
    text = README.read_text(encoding="utf-8")
    if args.update:
        README.write_text(update(text, slow=args.slow), encoding="utf-8")
        text = README.read_text(encoding="utf-8")
    problems = check(text, slow=args.slow)
    for problem in problems:
        print(problem, file=sys.stderr)
    print(f"README tour: {len(commands(text))} commands, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    raise SystemExit(main())
