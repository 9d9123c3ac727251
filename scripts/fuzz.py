"""Fuzz the G-code interpreter: grammar-generated and mutated programs against ``interpret``, and a sample
of them through the ``cnc-gym trace`` console command.

    .venv/bin/python scripts/fuzz.py --seed 1 --programs 20000 --save fuzz-out
    .venv/bin/python scripts/fuzz.py --seconds 600 --json

Every program ends in one outcome class:

=================  ===========================================================================================
``ok``             a tool path with finite numbers
``error:CODE``     a ``ProgramError``, its line ``FILE:LINE: message [CODE]`` one bounded line
``crash:TYPE``     any other exception, a tool path with NaN/inf (``crash:non-finite``), or an error line that
                   breaks the contract (``crash:bad-error-line``: not one bounded line naming the file and
                   a line ≥ 1)
``over-time``      more than ``--time-limit`` CPU seconds in ``interpret`` (default 10), though ``interpret``
                   runs with ``max_seconds`` = half of it: the interpreter missed its own time bound
``over-memory``    a ``MemoryError`` under ``--memory-limit`` (MiB above the worker's start), or the
                   worker killed
``cli-mismatch``   the console command (a subprocess, every ``--cli-every``-th program) disagrees with
                   ``interpret``: another exit status or code, stdout on an error, a traceback, not one
                   line
=================  ===========================================================================================

Programs run in a worker process (forked once, restarted after an over-time kill or a memory failure), so
a runaway program cannot take the fuzzer down. ``--save DIR`` keeps every program of the bad classes
(``crash``, ``over-time``, ``over-memory``, ``cli-mismatch``) with its outcome, to reproduce:
``cnc-gym trace DIR/crash-ValueError/0001.nc``. The exit status is 1 when any program fell in a bad class.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import random
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

BAD_PREFIXES = ("crash", "over-time", "over-memory", "cli-mismatch")

# ====================================================================================== grammar
FUNCTIONS = ["SIN", "COS", "TAN", "ATAN", "ASIN", "ACOS", "SQRT", "ABS", "ROUND", "FIX", "FUP", "LN", "EXP",
             "BIN", "BCD"]  # fmt: skip
OPERATORS = ["+", "-", "*", "/", "MOD", "AND", "OR", "XOR"]
COMPARISONS = ["EQ", "NE", "GT", "GE", "LT", "LE"]
EXTREME_NUMBERS = ["0", "0.", ".5", "0.0001", "999999.9999", "99999999", "0.00000001", "12345678.9",
                   "1.23456.7", "1..2", "00000000001", "1E5", "-0", "0.00005", "1" + "0" * 30]  # fmt: skip
VARIABLES = ["1", "2", "3", "4", "24", "25", "26", "100", "101", "500"]
ODD_VARIABLES = ["0", "33", "34", "[#1]", "[#2+1]", "5001", "5021", "4001", "4003", "3001", "3004", "2001",
                 "10001", "1000", "4109", "4130", "5061", "4120"]  # fmt: skip
#: Words the pocket and boss cycles take besides X Y Z R I J D Q L (cycles.CYCLE_WORDS).
POCKET_WORDS = {**dict.fromkeys((110, 111, 114, 115), "KWV"), **dict.fromkeys((112, 113, 116, 117), "K"),
                **dict.fromkeys((130, 131), "WVUK"), **dict.fromkeys((134, 135), "WVEUK"),
                **dict.fromkeys((132, 133, 136, 137), "UK")}  # fmt: skip
MODES = ["G90", "G91", "G17", "G18", "G19", "G61", "G64", "G94", "G40", "G49", "G80", "G67", "G69", "G50",
         "G50.1", "G15", "G98", "G99", "M03 S1000", "M04 S500", "M05", "M08", "M09", "T1 M06", "T2", "M00",
         "M01", "G54", "G55", "G59", "G09 G01 X1"]  # fmt: skip


class Grammar:
    """Random programs in the GSK 25i language. ``odd`` is the chance of an unusual or wrong choice at each
    decision: a clean program (odd = 0) mostly runs to its end, so the generator reaches deep into the
    interpreter; an odd one probes the error paths."""

    def __init__(self, rng: random.Random) -> None:
        self.rng = rng
        self.odd = 0.0

    def chance(self, p: float) -> bool:
        return self.rng.random() < p

    def number(self, *, positive: bool = False, small: bool = False) -> str:
        rng = self.rng
        r = rng.random()
        if self.chance(self.odd * 0.3):
            text = rng.choice(EXTREME_NUMBERS)
        elif r < 0.35:
            text = str(rng.randint(0, 10 if small else 100))
        elif r < 0.8:
            text = f"{rng.uniform(0, 5 if small else 150):.{rng.randint(1, 4)}f}"
        else:
            text = f"{rng.uniform(0, 2):.{rng.randint(1, 6)}f}"
        if not positive and rng.random() < 0.3:
            text = "-" + text
        return text

    def variable(self) -> str:
        if self.chance(self.odd):
            return "#" + self.rng.choice(ODD_VARIABLES)
        return "#" + self.rng.choice(VARIABLES)

    def expression(self, depth: int = 2) -> str:
        rng = self.rng
        r = rng.random()
        if depth <= 0 or r < 0.35:
            return self.variable() if rng.random() < 0.4 else self.number(positive=True)
        if r < 0.65:
            op = rng.choice(OPERATORS if self.chance(self.odd + 0.2) else ["+", "-", "*", "/"])
            return f"{self.expression(depth - 1)}{op}{self.expression(depth - 1)}"
        if r < 0.8:
            if rng.random() < 0.1:
                return f"POW[{self.expression(depth - 1)},{self.expression(depth - 1)}]"
            if rng.random() < 0.1:
                return f"ATAN[{self.expression(depth - 1)}]/[{self.expression(depth - 1)}]"
            name = rng.choice(
                FUNCTIONS if self.chance(self.odd + 0.3) else ["SIN", "COS", "ABS", "ROUND", "FIX"]
            )
            return f"{name}[{self.expression(depth - 1)}]"
        return f"[{self.expression(depth - 1)}]"

    def value(self, *, positive: bool = False) -> str:
        r = self.rng.random()
        if r < 0.85:
            return self.number(positive=positive)
        if r < 0.93:
            return ("-" if self.chance(0.2) else "") + self.variable()
        return f"[{self.expression(1)}]"

    def axes(self, letters: str = "XYZ") -> str:
        chosen = [a for a in letters if self.chance(0.6)] or [self.rng.choice(letters)]
        return " ".join(f"{a}{self.value()}" for a in chosen)

    def feed(self) -> str:
        return f" F{self.rng.randint(1, 5000)}" if self.chance(0.3) else ""

    # ------------------------------------------------------------------ blocks
    def motion(self) -> list[str]:
        rng = self.rng
        code = rng.choice(["G00", "G01", "G01", "G02", "G03", "", ""])
        corner = f" ,{rng.choice('LR')}{self.number(positive=True, small=True)}" if self.chance(0.05) else ""
        if code not in ("G02", "G03"):
            return [f"{code} {self.axes()}{self.feed()}{corner if code == 'G01' else ''}".strip()]
        plane = rng.choice(["G17", "G17", "G18", "G19"])
        u, v, w = {"G17": ("X", "Y", "Z"), "G18": ("Z", "X", "Y"), "G19": ("Y", "Z", "X")}[plane]
        i, j = {"G17": ("I", "J"), "G18": ("K", "I"), "G19": ("J", "K")}[plane]
        if self.chance(self.odd + 0.05):  # anything goes
            centre = (
                f"R{self.value()}"
                if self.chance(0.5)
                else " ".join(f"{c}{self.value()}" for c in rng.sample("IJK", rng.randint(1, 2)))
            )
            return [f"{plane} {code} {self.axes()} {centre}{self.feed()}{corner}"]
        # A consistent incremental arc: centre offset (a, b), end on the circle, maybe a helix.
        a, b = rng.uniform(-50, 50), rng.uniform(-50, 50)
        radius, turn = math.hypot(a, b), rng.uniform(0, 2 * math.pi)
        du = a - radius * math.cos(math.atan2(b, a) + turn)
        dv = b - radius * math.sin(math.atan2(b, a) + turn)
        helix = f" {w}{rng.uniform(-5, 5):.3f}" if self.chance(0.2) else ""
        if self.chance(0.5):
            r_word = radius if turn <= math.pi else -radius
            centre = f"R{r_word:.4f}"
        else:
            centre = f"{i}{a:.4f} {j}{b:.4f}"
        return [f"{plane} G91 {code} {u}{du:.4f} {v}{dv:.4f}{helix} {centre}{self.feed()}", "G90 G01"]

    def mode(self) -> list[str]:
        rng = self.rng
        choices = [*MODES, f"S{rng.randint(0, 12000)}", f"G04 P{rng.randint(0, 3000)}",
                   f"F{rng.randint(1, 8000)}", f"G04 X{self.number(positive=True, small=True)}"]  # fmt: skip
        if self.chance(self.odd):
            choices += ["M29 S100", "G20", "G21", "G29 X0"]
        return [rng.choice(choices)]

    def coordinates(self) -> list[str]:
        rng = self.rng
        makers = [
            lambda: [f"G52 {self.axes()}"],
            lambda: [f"G92 {self.axes()}"],
            lambda: [f"G10 L2 P{rng.randint(0, 6)} {self.axes()}"],
            lambda: [f"G10 L{rng.choice([10, 11, 12, 13])} P{rng.randint(1, 20)} R{self.number(small=True)}"],
            lambda: [f"G54.1 P{rng.randint(1, 48)}"],
            lambda: [f"G{rng.choice(['28', '28', '30', '27', '29'])} {self.axes()}"],
            lambda: [f"G53 {self.axes()}"],
            lambda: [f"G68 X{self.value()} Y{self.value()} R{self.number()}"],
            lambda: [rng.choice([f"G51 X{self.value()} Y{self.value()} P{self.number(small=True)}",
                                 f"G51.1 X{self.value()}", "G51 X0 Y0 I2 J1 K-1"]),
                     *self.motion(), "G50 G50.1"],
            lambda: ["G16", f"G01 X{self.number(positive=True)} Y{self.number()} F100", "G15"],
        ]  # fmt: skip
        return rng.choice(makers)()

    def compensation(self) -> list[str]:
        rng = self.rng
        r = rng.randrange(5)
        if r == 0:
            return [
                f"G10 L12 P1 R{self.number(positive=True, small=True)}",
                f"G{rng.choice([41, 42])} D1 G01 {self.axes('XY')} F300",
                *(f"G01 {self.axes('XY')}" for _ in range(rng.randint(1, 5))),
                f"G40 G01 {self.axes('XY')}",
            ]
        if r == 1:
            return [f"G10 L10 P2 R{self.number(small=True)}", f"G{rng.choice([43, 44])} H2 Z{self.value()}"]
        if r == 2:
            return [f"G{rng.choice([45, 46, 47, 48])} G01 {self.axes('XY')} D{rng.randint(0, 5)} F200"]
        if r == 3:
            return [
                "G10 L12 P3 R2",
                "G41 D3 G01 X10 Y0 F100",
                f"G39 I{self.number()} J{self.number()}",
                "Y10",
                "G40 X0 Y0",
            ]
        return ["G49", "G40"]

    def cycle(self) -> list[str]:
        rng = self.rng
        r = rng.random()
        if r < 0.6:
            code = rng.choice([73, 74, 76, 81, 82, 83, 84, 85, 86, 87, 88, 89])
            words = [
                f"G{rng.choice([98, 99])} G{code}",
                self.axes("XY"),
                f"Z-{self.number(positive=True)}",
                f"R{self.number(positive=True, small=True)}",
            ]
            if code in (73, 83) or self.chance(0.1):
                words.append(f"Q{self.number(positive=True, small=True)}")
            if self.chance(0.3):
                words.append(f"P{rng.randint(0, 2000)}")
            if self.chance(0.3):
                words.append(f"K{rng.choice([0, 1, 2, 5, 99, 9999])}")
            if code == 87:
                words[2:4] = [f"Z-{rng.randint(1, 10)}", f"R-{rng.randint(11, 30)}"]  # back boring: Z above R
            if code in (74, 84) and self.chance(0.3):
                words[0] = "M29 S100\n" + words[0]
            more = [self.axes("XY") for _ in range(rng.randint(0, 4))]
            if self.chance(0.3):
                k = rng.randint(0, 60)
                more.append(
                    f"G{rng.choice([120, 121, 122, 123])} X0 Y0 I{rng.randint(1, 20)} J{rng.randint(1, 20)} "
                    f"P{rng.randint(1, 60)} K{k}"
                )
            return [" ".join(words) + f" F{rng.randint(10, 2000)}", *more, "G80"]
        if r < 0.8:
            code = rng.choice([120, 121, 122, 123, 124, 125, 126, 127])
            words = [f"G{code}", self.axes("XY"), f"I{self.number(positive=True)}", f"J{self.number()}"]
            if code < 126:
                words.append(f"K{rng.randint(0, 40)}")
            if code in (122, 123, 124, 125):
                words.append(f"P{rng.randint(1, 40)}")
            if code >= 124:
                words += [
                    f"R{self.number(positive=True, small=True)}",
                    f"Z-{self.number(positive=True, small=True)}",
                ]
            if code >= 126:
                words.append(f"L{self.number(positive=True, small=True)}")
            if code in (124, 125):
                words.insert(0, "G81")
            return [" ".join(words) + f" F{rng.randint(10, 2000)}", "G80"]
        code = rng.choice([*range(110, 118), *range(130, 138)])
        words = [
            f"G{code}",
            self.axes("XY"),
            f"Z-{self.number(positive=True, small=True)}",
            "R2",
            f"I{self.number(positive=True)}",
            f"J{self.number(positive=True)}",
            f"D{rng.randint(0, 3)}",
            f"Q{self.number(positive=True, small=True)}",
            f"L{self.number(positive=True, small=True)}",
        ]
        allowed = POCKET_WORDS[code] if not self.chance(self.odd) else "KWVUE"
        words += [
            f"{c}{self.number(positive=True, small=True)}"
            for c in "KWVUE"
            if c in allowed and self.chance(0.3)
        ]
        return ["G10 L12 P1 R1", " ".join(words) + f" F{rng.randint(10, 2000)}", "G80"]

    def nurbs(self) -> list[str]:
        rng = self.rng
        rank = rng.choice([2, 3, 4, 4, 5] if self.chance(self.odd) else [2, 3, 4, 4])
        n = rng.randint(rank, 12)
        inner = [k / 1000 for k in sorted(rng.sample(range(1, 1000), n - rank))]
        extreme = ["1", "0.01", "100", "0.001", "1000"] + (["0.0001"] if self.chance(self.odd) else [])
        weights = rng.choice([None, None, ["1", "0.5", "2", "0.7"], extreme])
        lines = ["G05 P10000", "G90 G00 X0 Y0 Z0"]
        weight = (lambda: f" R{rng.choice(weights)}") if weights else (lambda: "")
        lines.append(f"G06.2 P{rank} K0 X0 Y0 Z0{weight()} F{rng.randint(10, 3000)}")
        scale = rng.choice([1, 10, 100, 1000])
        for i in range(1, n):
            knot = 0 if i < rank else inner[i - rank]
            point = (
                " ".join(f"{a}{rng.uniform(-scale, scale):.3f}" for a in "XYZ" if self.chance(0.7)) or "X1"
            )
            lines.append(f"K{knot} {point}{weight()}")
        lines += ["K1"] * rank
        lines += ["G05 P0", "G00"]
        return lines

    def loop(self, depth: int = 1) -> list[str]:
        rng = self.rng
        counter = f"#{rng.choice([1, 2, 3, 100, 101])}"
        if depth >= 3:
            return [f"{counter}={self.expression()}"]
        bound = (
            rng.choice([1, 2, 3, 5, 10, 50, 200, 1000, 100000]) if self.chance(0.5) else self.expression(1)
        )
        step = rng.choice(["1", "1", "0.5", "2", "-1", "0"]) if self.chance(self.odd + 0.1) else "1"
        body = [line for _ in range(rng.randint(1, 4)) for line in self.block(depth + 1)]
        if rng.random() < 0.5:
            m = depth + 1
            return [
                f"{counter}=0",
                f"WHILE[{counter}LT{bound}]DO{m}",
                *body,
                f"{counter}={counter}+{step}",
                f"END{m}",
            ]
        n = rng.randint(1, 99)
        return [
            f"{counter}=0",
            f"N{n}",
            *body,
            f"{counter}={counter}+{step}",
            f"IF[{counter}LT{bound}]GOTO{n}",
        ]

    def macro(self, depth: int = 1) -> list[str]:
        rng = self.rng
        r = rng.randrange(10)
        if r < 3:
            return [f"{self.variable()}={self.expression()}"]
        if r == 3 and depth < 4:
            return self.loop(depth)
        if r == 4:
            cond = f"[{self.expression(1)}{rng.choice(COMPARISONS)}{self.expression(1)}]"
            return [f"IF{cond}THEN{self.variable()}={self.expression(1)}"]
        if r == 5:
            return [
                rng.choice(
                    [
                        "M98 P1",
                        "M98 P2",
                        f"M98 P1 L{rng.randint(1, 20)}",
                        f"M98 P{rng.randint(2, 99)}0001",
                        "M98 P9000 L0" if self.chance(self.odd) else "M98 P2",
                    ]
                )
            ]
        if r == 6:
            args = " ".join(f"{c}{self.value()}" for c in rng.sample("ABCIJKXYZRF", rng.randint(0, 4)))
            return [f"G65 P9000 {args}" + (f" L{rng.randint(1, 20)}" if self.chance(0.2) else "")]
        if r == 7:
            return [
                f"G66 P9000 {self.axes()}",
                *(f"G91 G00 {self.axes('XY')}" for _ in range(2)),
                "G67",
                "G90",
            ]
        if r == 8 and self.chance(self.odd + 0.05):
            return [
                rng.choice(
                    [
                        f"#3000={rng.randint(1, 200)} (ALARM)",
                        "#3006=1 (STOP)",
                        f"#3004={rng.randint(0, 7)}",
                        f"GOTO{rng.randint(1, 99)}",
                        f"END{rng.randint(1, 3)}",
                        "M99",
                    ]
                )
            ]
        return [f"#{rng.randint(1, 3)}={self.variable()}+1"]

    def block(self, depth: int = 0) -> list[str]:
        rng = self.rng
        make = rng.choices(
            [self.motion, self.mode, self.coordinates, self.compensation, self.cycle, self.macro, self.nurbs],
            weights=[12, 3, 2, 2, 2, 4, 0.6],
        )[0]
        lines = make(depth) if make == self.macro else make()
        if self.chance(0.1):
            lines[0] = f"N{rng.randint(100, 9999)} {lines[0]}"
        if self.chance(0.03) and not lines[0].startswith("#"):
            lines[0] = rng.choice(["/", "/2 ", "/1/3 "]) + lines[0]
        if self.chance(0.05):
            lines[-1] += rng.choice([" (COMMENT)", " ( a comment; with ( odd text )", ";"])
        return lines

    def program(self) -> str:
        rng = self.rng
        self.odd = rng.choice([0.0, 0.0, 0.0, 0.01, 0.05, 0.2])
        lines = ["%"] if self.chance(0.2) else []
        if self.chance(0.3):
            lines.append(f"O{rng.randint(1000, 8999):04d}")
        lines.append(rng.choice(["G90 G17 G21 G40 G49 G80", "G90", "G91 G20", "", "G54 G90 G00 X0 Y0 Z10"]))
        lines.append(f"F{rng.randint(10, 5000)}")
        for _ in range(rng.randint(1, 30)):
            lines += self.block()
        lines.append(rng.choice(["M30", "M30", "M02", "M99", ""]))
        for number_ in (1, 2, 9000):
            lines.append(f"O{number_}")
            lines += [line for _ in range(rng.randint(0, 4)) for line in self.block(depth=2)]
            lines.append("M99")
        return "\n".join(lines) + "\n"


# ====================================================================================== mutation
SEEDS = [
    "G90 G54 G17 G21\nS8000 M03\nG00 X0 Y30 Z5\nG01 Z-1 F600\nG01 X-6.735 Y9.271 F4000\nX-28.532 Y9.271\n"
    "G02 X10 Y0 R20\nG03 X0 Y10 I-10 J0\nG00 Z5\nM30\n",
    "#1=0\nWHILE[#1LT3]DO1\nG01 X#1 F100\n#1=#1+1\nEND1\nM98 P5\nG65 P6 A1 I2 I3\nM30\n"
    "O5\nG91 G01 Y1\nG90\nM99\nO6\nIF[#1EQ#0]GOTO9\nG00 Z#4\nN9 M99\n",
    "G66 P7 R-2 Z-1\nG91 G00 X10\nY10\nG67\nM30\nO7\nG00 Z#18\nG01 Z#26 F50\nG00 Z-[#18+#26]\nM99\n",
    "G90 G00 Z10\nG99 G83 X10 Y10 Z-20 R5 Q2 F100\nX20\nG98 G73 X30 Z-10 R2 Q1 K3\nG80\n"
    "G81 Z-5 R2 F200 K0\nG123 X0 Y0 I10 J10 P3 K2\nG80\nM30\n",
    "G05 P10000\nG00 X0 Y0\nG06.2 P3 K0 X0 Y0 F600\nK0 X10 Y0 R0.7\nK0 X10 Y10\nK1\nK1\nK1\nG05 P0\nM30\n",
    "G10 L12 P1 R5\nG41 D1 G01 X10 Y0 F300\nY10\nG02 X0 Y20 R10\nG40 G01 X-5 Y0\nG43 H1 Z5\nG49\nM30\n",
    "G68 X0 Y0 R30\nG51 X0 Y0 P1500\nG01 X10 Y10 F100\nG50\nG69\nG52 X5\nG92 X0 Y0\nG28 Z0\nM30\n",
    "G110 X0 Y0 Z-5 R2 I10 J5 D0 Q2 L3 F300\nG80\nG126 X0 Y0 I20 J10 L4 Z-1 R2 F300\nM30\n",
]
FRAGMENTS = ["#", "[", "]", "=", "GOTO", "DO1", "END1", "WHILE", "IF", "M99", "(", ")", ";", "%", "/", ",L",
             ",R", "G06.2", "K", "R0.0001", "Q0.001", "K9999", "L999", "P99", "G91", "N1", "99999999",
             "0.0001", "-", ".", "..", "²", "١", "ı", "é", "X", "Y", "Z", "I", "J", "F0", "G02", "G03", "G17",
             "G18", "M98 P1", "G65 P1", "#3000=1", "1" + "0" * 40, "\n", "\r", "\t", "\x00", "\x1b[2J",
             "\u00a0", "\u2028"]  # fmt: skip


def mutate(grammar: Grammar, text: str, corpus: list[str]) -> str:
    """1-4 edits of ``text``: fragments, deletions, odd characters, repeated, swapped or spliced lines, an
    extreme number, a fresh block, a cut."""
    rng = grammar.rng
    grammar.odd = 0.2
    for _ in range(rng.randint(1, 4)):
        lines = text.split("\n")
        r = rng.randrange(9)
        i = rng.randrange(len(lines))
        if r == 0:  # insert a fragment
            pos = rng.randint(0, len(text))
            text = text[:pos] + rng.choice(FRAGMENTS) + text[pos:]
        elif r == 1:  # delete a span
            pos = rng.randint(0, len(text))
            text = text[:pos] + text[pos + rng.randint(1, 8) :]
        elif r == 2:  # replace a character
            pos = rng.randrange(len(text)) if text else 0
            text = (
                text[:pos]
                + chr(rng.choice([rng.randint(32, 126), rng.randint(0, 31), rng.randint(128, 0x2FFF)]))
                + text[pos + 1 :]
            )
        elif r == 3:  # duplicate lines
            lines[i:i] = lines[i : i + rng.randint(1, 3)] * rng.randint(1, 5)
            text = "\n".join(lines)
        elif r == 4:  # swap two lines
            j = rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines)
        elif r == 5:  # splice lines of another program
            other = rng.choice(corpus).split("\n")
            k = rng.randrange(len(other))
            lines[i:i] = other[k : k + rng.randint(1, 6)]
            text = "\n".join(lines)
        elif r == 6:  # a number made extreme
            digits = [k for k, c in enumerate(text) if c.isdigit()]
            if digits:
                pos = rng.choice(digits)
                text = (
                    text[:pos]
                    + rng.choice(["0", "9" * rng.randint(2, 12), "0.0001", "1" + "0" * 20, "00"])
                    + text[pos + 1 :]
                )
        elif r == 7:  # a fresh block
            lines[i:i] = grammar.block()
            text = "\n".join(lines)
        else:  # truncate
            text = text[: rng.randint(0, len(text))]
    return text


def programs(seed: int):
    """Endless (kind, text): grammar programs, and mutations of seeds and earlier grammar programs."""
    rng = random.Random(seed)
    grammar = Grammar(rng)
    corpus = list(SEEDS)
    while True:
        if rng.random() < 0.5:
            text = grammar.program()
            if len(corpus) < 400:
                corpus.append(text)
            else:
                corpus[rng.randrange(len(SEEDS), len(corpus))] = text
            yield "grammar", text
        else:
            yield "mutated", mutate(grammar, rng.choice(corpus), corpus)


# ====================================================================================== running
class _OverTime(BaseException):
    """Raised by the CPU-time alarm inside the worker (a BaseException: no ``except Exception`` eats it)."""


def _on_alarm(signum, frame):
    raise _OverTime


def _classify(text: str, time_limit: float, dialect: str = "gsk25i") -> tuple[str, float, str]:
    """(outcome, CPU seconds, detail) of one program in this process. ``interpret`` runs under the time
    bound ``max_seconds`` = ``time_limit`` / 2 (its ``time-budget`` error is an ordinary outcome); the
    CPU-time alarm at ``time_limit`` catches a program that gets past that bound."""
    import numpy as np

    from cnc_gym.errors import MAX_LINE_CHARS, ProgramError
    from cnc_gym.gcode import interpret

    start = time.process_time()
    signal.setitimer(signal.ITIMER_PROF, time_limit)
    try:
        tp = interpret(text, file="fuzz.nc", dialect=dialect, max_seconds=time_limit / 2)
    except _OverTime:
        return "over-time", time.process_time() - start, ""
    except ProgramError as err:
        line = str(err)
        good = (bool(err.code) and "\n" not in line and len(line) <= MAX_LINE_CHARS and err.line >= 1
                and line.startswith("fuzz.nc:"))  # fmt: skip
        return (
            (f"error:{err.code}" if good else "crash:bad-error-line"),
            time.process_time() - start,
            line[:300],
        )
    except MemoryError:
        return "over-memory", time.process_time() - start, ""
    except BaseException as exc:
        import traceback

        where = traceback.extract_tb(exc.__traceback__)[-1]
        detail = f"{type(exc).__name__}: {str(exc)[:200]} at {Path(where.filename).name}:{where.lineno}"
        return f"crash:{type(exc).__name__}", time.process_time() - start, detail
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
    seconds = time.process_time() - start
    for name in ("start", "end", "radius", "sweep", "dwell_s", "length", "s_start"):
        if not np.all(np.isfinite(getattr(tp, name))):
            return "crash:non-finite", seconds, name
    cutting = (tp.kind == 1) | (tp.kind == 2) | (tp.kind == 4)
    if not np.all(np.isfinite(tp.feed[cutting])):
        return "crash:non-finite", seconds, "feed"
    return "ok", seconds, ""


def _worker(conn, time_limit: float, memory_limit_mb: float) -> None:
    signal.signal(signal.SIGPROF, _on_alarm)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles ^C
    try:
        with open("/proc/self/status") as status:
            vm = next(int(line.split()[1]) for line in status if line.startswith("VmSize:")) * 1024
        limit = int(vm + memory_limit_mb * 2**20)
        resource.setrlimit(resource.RLIMIT_AS, (limit, resource.getrlimit(resource.RLIMIT_AS)[1]))
    except (OSError, ValueError, StopIteration):
        pass  # no /proc or no permission: run without the memory bound
    import cnc_gym.gcode  # noqa: F401 - import once, before the first program's clock starts

    while True:
        try:
            text, dialect = conn.recv()
        except EOFError:
            return
        outcome = _classify(text, time_limit, dialect)
        conn.send((*outcome, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024))


class _Worker:
    def __init__(self, time_limit: float, memory_limit_mb: float) -> None:
        self.time_limit, self.memory_limit_mb = time_limit, memory_limit_mb
        self.process: multiprocessing.process.BaseProcess | None = None
        self.conn: Any = None  # multiprocessing.connection.Connection

    def start(self) -> None:
        context = multiprocessing.get_context("fork")
        self.conn, child = context.Pipe()
        self.process = context.Process(
            target=_worker, args=(child, self.time_limit, self.memory_limit_mb), daemon=True
        )
        self.process.start()
        child.close()

    def stop(self) -> None:
        if self.process is not None:
            self.process.kill()
            self.process.join()
            self.conn.close()
            self.process = None

    def run(self, text: str, dialect: str = "gsk25i") -> tuple[str, float, str, float]:
        if self.process is None:
            self.start()
        self.conn.send((text, dialect))
        # The CPU alarm ends a slow program inside the worker; this backstop catches one stuck in a long C
        # call (the alarm runs only between Python bytecodes): the worker's own CPU time, read from /proc
        # (wall time on a loaded machine says little), and a far wall-clock limit.
        process = self.process
        assert process is not None
        cpu_limit, wall_limit = 2 * self.time_limit + 10, 30 * self.time_limit + 300
        cpu_start, wall_start = _cpu_seconds(process.pid), time.monotonic()
        while not self.conn.poll(1.0):
            cpu = _cpu_seconds(process.pid)
            over_cpu = cpu is not None and cpu_start is not None and cpu - cpu_start > cpu_limit
            if over_cpu or time.monotonic() - wall_start > wall_limit or not process.is_alive():
                break
        else:
            try:
                outcome, seconds, detail, rss = self.conn.recv()
                if outcome == "over-memory":
                    self.stop()  # a fresh worker: the failed allocation may have left the heap fragmented
                return outcome, seconds, detail, rss
            except EOFError:
                pass
        alive, code = process.is_alive(), process.exitcode
        self.stop()
        if alive:
            return "over-time", cpu_limit, "killed by the backstop: no answer", 0.0
        return "over-memory", 0.0, f"worker died (exit {code})", 0.0


def _cpu_seconds(pid: int | None) -> float | None:
    """User + system CPU seconds of process ``pid`` (Linux /proc), None where that cannot be read."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            fields = stat.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def _cli_command() -> list[str]:
    script = Path(sys.executable).with_name("cnc-gym")
    if script.exists():
        return [str(script)]
    found = shutil.which("cnc-gym")
    return [found] if found else [sys.executable, "-m", "cnc_gym.cli"]


def check_cli(text: str, outcome: str, time_limit: float, dialect: str = "gsk25i") -> str:
    """'' when ``cnc-gym trace`` agrees with the in-process outcome, else what differs."""
    with tempfile.TemporaryDirectory() as folder:  # an empty folder: M98/G65 find no other program files
        path = Path(folder) / "fuzz.nc"
        path.write_bytes(text.encode("utf-8", "surrogatepass"))
        try:
            done = subprocess.run(
                [*_cli_command(), "trace", str(path), "--dialect", dialect],
                capture_output=True,
                timeout=4 * time_limit + 60,
            )
        except subprocess.TimeoutExpired:
            return "timeout" if outcome != "over-time" else ""
    out, err = done.stdout.decode("utf-8", "replace"), done.stderr.decode("utf-8", "replace")
    if "Traceback" in err:
        return "traceback: " + err.strip().splitlines()[-1][:200]
    if outcome == "ok":
        if done.returncode != 0 or err:
            return f"exit {done.returncode} for an ok program: {err.strip()[:200]}"
        try:
            [json.loads(line) for line in out.splitlines()]
        except ValueError:
            return "stdout is not JSON Lines"
        return ""
    if outcome.startswith("error:"):
        code = outcome.split(":", 1)[1]
        if done.returncode != 2 or out or err.count("\n") != 1 or not err.rstrip().endswith(f"[{code}]"):
            return (
                f"exit {done.returncode}, stdout {len(out)} chars, stderr {err.strip()[:200]!r} for {outcome}"
            )
    return ""


@dataclass
class Report:
    seed: int
    tried: int = 0
    by_kind: Counter = field(default_factory=Counter)
    by_dialect: Counter = field(default_factory=Counter)
    outcomes: Counter = field(default_factory=Counter)
    cli_checked: int = 0
    slowest: list = field(default_factory=list)  # (cpu seconds, outcome, index), the 5 slowest
    peak_rss_mb: float = 0.0
    seconds: float = 0.0
    bad: list = field(default_factory=list)  # (index, kind, outcome, detail, text)

    def classes(self) -> dict[str, int]:
        """Outcome classes (ok / error / crash / over-time / over-memory / cli-mismatch) and counts."""
        out: Counter = Counter()
        for outcome, n in self.outcomes.items():
            out[outcome.split(":")[0]] += n
        return dict(out)

    def as_dict(self) -> dict:
        return {
            "seed": self.seed,
            "programs": self.tried,
            "by_kind": dict(self.by_kind),
            "by_dialect": dict(self.by_dialect),
            "classes": self.classes(),
            "outcomes": dict(self.outcomes.most_common()),
            "cli_checked": self.cli_checked,
            "slowest": self.slowest,
            "peak_rss_mb": round(self.peak_rss_mb),
            "seconds": round(self.seconds, 1),
            "bad": [{"index": i, "kind": k, "outcome": o, "detail": d} for i, k, o, d, _ in self.bad],
        }


def fuzz(
    *,
    seed: int = 0,
    programs_budget: int | None = 1000,
    seconds: float | None = None,
    time_limit: float = 10.0,
    memory_limit_mb: float = 2048.0,
    cli_every: int = 500,
    save: Path | None = None,
    progress: bool = False,
    dialects: Sequence[str] = ("gsk25i",),
) -> Report:
    """Run the fuzzer until ``programs_budget`` programs or ``seconds`` (whichever first). Program ``i``
    runs under ``dialects[i % len(dialects)]`` (the grammar is the Fanuc family's: in another language
    family most programs are errors, which still checks that every outcome is one clean line)."""
    report = Report(seed=seed)
    worker = _Worker(time_limit, memory_limit_mb)
    started = time.monotonic()
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=programs_budget, unit="program", disable=None, file=sys.stderr)
    try:
        for index, (kind, text) in enumerate(programs(seed)):
            if programs_budget is not None and index >= programs_budget:
                break
            if seconds is not None and time.monotonic() - started >= seconds:
                break
            dialect = dialects[index % len(dialects)]
            outcome, cpu, detail, rss = worker.run(text, dialect)
            report.tried += 1
            report.by_kind[kind] += 1
            report.by_dialect[dialect] += 1
            report.peak_rss_mb = max(report.peak_rss_mb, rss)
            report.slowest = sorted([*report.slowest, (round(cpu, 3), outcome, index)], reverse=True)[:5]
            checkable = not outcome.startswith(BAD_PREFIXES) and outcome != "error:time-budget"
            if cli_every and index % cli_every == 0 and checkable:
                report.cli_checked += 1
                problem = check_cli(text, outcome, time_limit, dialect)
                if problem:
                    outcome, detail = "cli-mismatch", problem
            report.outcomes[outcome] += 1
            if outcome.startswith(BAD_PREFIXES):
                report.bad.append((index, kind, outcome, detail, text))
                if save is not None:
                    _save(save, index, outcome, detail, text)
            if bar is not None:
                bar.update()
                if index % 50 == 0:
                    bar.set_postfix(bad=len(report.bad))
    finally:
        worker.stop()
        if bar is not None:
            bar.close()
    report.seconds = time.monotonic() - started
    return report


def _save(folder: Path, index: int, outcome: str, detail: str, text: str) -> None:
    where = folder / outcome.replace(":", "-")
    where.mkdir(parents=True, exist_ok=True)
    (where / f"{index:07d}.nc").write_bytes(text.encode("utf-8", "surrogatepass"))
    (where / f"{index:07d}.txt").write_text(detail + "\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--programs", type=int, default=None, help="programs to try (default 10000 without --seconds)"
    )
    parser.add_argument("--seconds", type=float, default=None, help="wall-clock budget in seconds")
    parser.add_argument(
        "--time-limit", type=float, default=10.0, help="CPU seconds one program may take (10)"
    )
    parser.add_argument("--memory-limit", type=float, default=2048.0, help="MiB one program may add (2048)")
    parser.add_argument(
        "--cli-every",
        type=int,
        default=500,
        help="every N-th program also runs through `cnc-gym trace` (default 500; 0 = never)",
    )
    parser.add_argument("--save", type=Path, default=None, help="folder for the programs of the bad classes")
    parser.add_argument("--json", action="store_true", help="print the report as one JSON object")
    parser.add_argument(
        "--dialect",
        default="gsk25i",
        help="dialect name, a comma-separated list taken in turn, or 'all' (every registered dialect); "
        "default gsk25i",
    )
    args = parser.parse_args(argv)
    from cnc_gym.gcode import DIALECT_MODULES

    built = sorted(name for name, module in DIALECT_MODULES.items() if module)
    dialects = built if args.dialect == "all" else args.dialect.split(",")
    unknown = [name for name in dialects if name not in built]
    if unknown:
        parser.error(f"unknown dialect {unknown[0]!r}: choose from {', '.join(built)} or all")
    budget = args.programs if args.programs is not None else (None if args.seconds else 10_000)
    report = fuzz(
        seed=args.seed,
        programs_budget=budget,
        seconds=args.seconds,
        time_limit=args.time_limit,
        memory_limit_mb=args.memory_limit,
        cli_every=args.cli_every,
        save=args.save,
        progress=not args.json,
        dialects=dialects,
    )
    if args.json:
        print(json.dumps(report.as_dict()))
    else:
        print(
            f"seed {report.seed}: {report.tried} programs "
            f"({dict(report.by_kind)}; {dict(report.by_dialect)}) "
            f"in {report.seconds:.0f} s, "
            f"{report.cli_checked} also through `cnc-gym trace`; "
            f"worker peak RSS {report.peak_rss_mb:.0f} MiB"
        )
        for name, n in sorted(report.classes().items(), key=lambda kv: -kv[1]):
            print(f"  {name:<14} {n:>8}  {100 * n / max(report.tried, 1):6.2f} %")
        common = report.outcomes.most_common()
        codes = [f"{o.split(':', 1)[1]} {n}" for o, n in common if o.startswith("error:")]
        print("  error codes:  " + ", ".join(codes))
        print(
            "  slowest (CPU s, outcome, program #): "
            + ", ".join(f"{s:.2f} {o} #{i}" for s, o, i in report.slowest)
        )
        for index, kind, outcome, detail, _ in report.bad[:30]:
            print(f"  BAD #{index} ({kind}) {outcome}: {detail}")
    return 1 if report.bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
