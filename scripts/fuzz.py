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
                   a line ≥ 1; ``crash:unregistered-code``: a code not in ``cnc_gym/error_codes.py``)
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


# ====================================================================================== targets
#: Characters by class, for the reader rules that look at a character's class (ASCII digits and letters are
#: program text; blanks are dropped; a comment, ';', '%', '/', '#', '[', ',' … start a construct; anything
#: else is an illegal character): each class in every position of ``CHARACTER_TEMPLATES``.
CHARACTER_CLASSES: dict[str, str] = {
    "ascii-digit": "0159",
    "unicode-digit": "²³¹١٢۳०১๓０９߁",  # str.isdigit() takes all of them; none is a digit of a program
    "unicode-letter": "ıéßﬁΩЖＧＸ",  # 'ı'.upper() == 'I', 'ﬁ'.upper() == 'FI', 'ß'.upper() == 'SS'
    "ascii-letter": "AEGLNOPXZ",
    "lower-case": "aegnoxz",
    "blank": " \t\v\f",
    "unicode-space": "\u00a0\u2003\u3000\u200b\ufeff",
    "line-break": "\r\n\x1c\x1d\x1e\x85\u2028\u2029",
    "control": "\x00\x07\x08\x1b\x7f",
    "structure": "()%;/#[]=,:$",
    "sign-point": "+-.",
    "punctuation": "*&!?<>@^_{}|~`\"'\\",
    "combining": "\u0301\u0338",
    "odd-code-point": "\ufffd\U0001f600\ud800",  # a replacement character, an emoji, a lone surrogate
}
#: Blocks with one character slot ``{c}``: every construct the readers have a rule for.
CHARACTER_TEMPLATES = [
    "{c}", "G01 X{c} F100", "G01 X1{c} F100", "G01 X{c}1 F100", "G0{c}1 X1", "G01 X1 F100{c}",
    "#1={c}", "#{c}=1", "#1=1{c}2", "#1=[{c}]", "#1=SIN[{c}]", "/{c} G01 X1 F100", "/1{c} G00 X1",
    "N{c} G00 X1", "N1{c} G00 X1", "O{c}", ":{c}", "%{c}", "GOTO{c}", "GOTO1{c}", "IF[{c}EQ1]GOTO1",
    "IF[#1EQ{c}]THEN#2=1", "WHILE[{c}LT1]DO1", "DO{c}", "END{c}", "M98 P{c}", "M98 P1 L{c}", "G65 P1 A{c}",
    "G00 X[1{c}2]", "G00 X1 ({c})", "G00 X1 ({c}", "({c}) G00 X1", "G01 X1 ,{c}1 F100", "G01 X1 ,L{c} F100",
    "G10 L2 P{c} X1", "G04 P{c}", "G04 X{c}", "${c}", "R{c}=1", "R1={c}", "L{c}", "G01 X1 Y2 {c} F100",
    "G02 X1 Y0 R{c} F100", "G81 X0 Y0 Z-1 R{c} F100", "{c}G00 X1", "G00{c}X1",
]  # fmt: skip
#: How a block ends: the ';'-terminated variants run every rule through the ';' path of the readers.
TERMINATORS = ["", "", ";", ";", "; (note)", ";G00 X1", " ;", ";;", "; move to X1"]
#: Odd numbers for any address: signs, exponents, Unicode digits, huge and tiny values, expressions.
ODD_NUMBERS = [
    "", "0", "-0", "+0", "+1", "-1", "--1", "+-1", "-+1", "1-", "1+", "1e3", "1E3", "1e-3", "1E+3", "1e",
    "e3", "1.5e2", "1.E2", ".5", "5.", ".", "1.2.3", "-.", "+.", "00000001", "99999999", "999999999",
    "9999999999999999", "9" * 40, "1" + "0" * 400, "0." + "0" * 30 + "1", "99999999.9999", "0.00000001",
    "-999999.9999", "1000000", "-1000000", "²", "1²", "١٢", "１", "#1", "-#1", "#-1", "#[1]", "[1]", "[-1]",
    "[1e3]", "#0", "#99999999", "#[1/0]", "[1/0]", "nan", "inf", "NaN", "Infinity", "0x10", "1_000", "1,5",
    "1 2", " 1", "1\t2", "[" * 7 + "1" + "]" * 7, "#" * 5 + "1", "[SQRT[-1]]", "[9" + "9" * 30 + "]",
]  # fmt: skip
ADDRESS_LETTERS = [chr(c) for c in range(ord("A"), ord("Z") + 1)] + [",L", ",R", ",C"]
#: Blocks with one word slot ``{w}``: the address letter in the company of the codes that give it meaning.
ADDRESS_CONTEXTS = [
    "{w}", "{w}", "G00 {w}", "G01 X1 {w} F100", "G02 X1 Y0 R1 {w} F100", "G03 X0 Y1 I-1 {w} F100",
    "G81 X0 Y0 Z-1 R1 {w} F100", "G83 X0 Y0 Z-2 R0 Q1 {w} F10", "G76 X0 Y0 Z-1 R1 Q1 {w} F100",
    "G65 P1 {w}", "G66 P1 {w}", "M98 P1 {w}", "G10 L2 P1 {w}", "G10 L12 P1 {w}", "G04 {w}", "G68 X0 Y0 {w}",
    "G51 X0 Y0 {w}", "G43 {w} Z1", "G41 D1 G01 X1 {w} F100", "G05 P10000 {w}", "N1 {w}", "G92 {w}",
    "G28 {w}", "G54.1 {w}", "G31 X1 {w} F100", "G37 {w}", "G110 X0 Y0 Z-5 R2 I10 J5 D0 Q2 L3 {w} F300",
    "G122 X0 Y0 I10 J0 K3 {w}", "G126 X0 Y0 I20 J10 L4 Z-1 R2 {w} F300", "M03 {w}", "T1 M06 {w}",
    "G16 {w}", "#1={w}", "IF[#1EQ1]GOTO{w}", "G22 X0 Y0 {w}", "G34 X0 Y0 {w}", "G134 X0 Y0 {w}",
    "$IF R1==1 {w}", "LL1 {w}", "G161 {w}",
]  # fmt: skip

#: Program kinds and their default weights in a run.
DEFAULT_MIX: dict[str, float] = {"grammar": 2, "mutated": 2, "characters": 3, "addresses": 3}


def character_program(rng: random.Random) -> str:
    """One character of one class in one construct, with or without a ';' end, in a small program."""
    chars = CHARACTER_CLASSES[rng.choice(list(CHARACTER_CLASSES))]
    c = rng.choice(chars)
    if rng.random() < 0.15:
        c = c * rng.randint(2, 3) if rng.random() < 0.5 else c + rng.choice(chars)
    block = rng.choice(CHARACTER_TEMPLATES).replace("{c}", c)
    if rng.random() < 0.2:
        block = block.lower()
    lines = [block + rng.choice(TERMINATORS)]
    if rng.random() < 0.5:
        lines.insert(0, rng.choice(["G90 G00 X0 Y0", "%", "O1", "N1 G00 X0", "#1=1", "G91", "(header)"]))
    if rng.random() < 0.5:
        lines.append(rng.choice(["M30", "G00 X1", "N1 M99", "%", "M02;"]))
    return "\n".join(lines) + rng.choice(["\n", "\n", "", "\r\n"])


def odd_number(rng: random.Random) -> str:
    """An odd number: one of ``ODD_NUMBERS``, or a built one (signs, leading zeros, a point, an exponent, a
    Unicode digit somewhere)."""
    if rng.random() < 0.5:
        return rng.choice(ODD_NUMBERS)
    sign = rng.choice(["", "", "", "-", "+", "--", "+-", "-+"])
    digits = rng.choice([str(rng.randint(0, 9)), str(rng.randint(0, 10 ** rng.randint(1, 30))),
                         "0" * rng.randint(1, 20) + "1", ""])  # fmt: skip
    point = rng.choice(["", "", ".", "." + str(rng.randint(0, 99999)), ".."])
    exponent = rng.choice(["", "", "", "e3", "E-2", "e+10", "E400", "e", "E-"])
    text = sign + digits + point + exponent
    if rng.random() < 0.15:
        at = rng.randint(0, len(text))
        text = text[:at] + rng.choice("²٣０߁") + text[at:]
    return text


def address_program(rng: random.Random) -> str:
    """Every address letter A-Z (and the ,L ,R ,C corner words) with an odd number, in a block of a code that
    gives it a meaning or of none, with or without a ';' end."""
    word = rng.choice(ADDRESS_LETTERS) + odd_number(rng)
    if rng.random() < 0.2:
        word += " " + rng.choice(ADDRESS_LETTERS) + odd_number(rng)
    block = rng.choice(ADDRESS_CONTEXTS).replace("{w}", word)
    if rng.random() < 0.15:
        block = block.lower()
    head = rng.choice(["G90 G00 X0 Y0 Z10", "G91", "G20", "M03 S1000", ""])
    lines = [head, block + rng.choice(TERMINATORS)]
    lines.append(rng.choice(["M30", "G80", "G40 G49 G80", ""]))
    if rng.random() < 0.5:
        lines += ["O1", "G00 X#1", "M99"]  # M98 P1 / G65 P1 find a program
    return "\n".join(line for line in lines if line) + "\n"


def program_at(seed: int, index: int, mix: dict[str, float] | None = None) -> tuple[str, str]:
    """Program ``index`` of the run with ``seed``: ``(kind, text)``, a pure function of the three (so a run
    restarts anywhere, a batch runs in any worker, and ``--save`` names what to reproduce)."""
    weights = mix or DEFAULT_MIX
    rng = random.Random(f"{seed}/{index}")
    kind = rng.choices(list(weights), list(weights.values()))[0]
    grammar = Grammar(rng)
    if kind == "grammar":
        return kind, grammar.program()
    if kind == "mutated":
        corpus = [*SEEDS, grammar.program()]
        base = corpus[-1] if rng.random() < 0.5 else rng.choice(SEEDS)
        return kind, mutate(grammar, base, corpus)
    if kind == "characters":
        return kind, character_program(rng)
    if kind == "addresses":
        return kind, address_program(rng)
    raise ValueError(f"unknown program kind {kind!r} (choose from {', '.join(DEFAULT_MIX)})")


def programs(seed: int, mix: dict[str, float] | None = None):
    """Endless ``(kind, text)``: :func:`program_at` for index 0, 1, 2 …"""
    index = 0
    while True:
        yield program_at(seed, index, mix)
        index += 1


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

    from cnc_gym.error_codes import CODES
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
        outcome = f"error:{err.code}" if good else "crash:bad-error-line"
        if good and err.code not in CODES:  # every code is declared in cnc_gym/error_codes.py
            outcome = "crash:unregistered-code"
        return outcome, time.process_time() - start, line[:300]
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


@dataclass
class Task:
    """A batch of programs for one worker: indices ``start`` … ``start + count - 1`` of the run."""

    seed: int
    start: int
    count: int
    dialects: tuple[str, ...]
    mix: dict[str, float]
    time_limit: float
    cli_every: int


@dataclass
class BatchResult:
    """What a worker sends back for a task: counts, not programs (only the bad ones and the few sampled for
    the console check travel back)."""

    done: int = 0  # programs run (fewer than the task's count after a memory failure)
    outcomes: Counter = field(default_factory=Counter)  # (dialect, kind, outcome) → programs
    slowest: list = field(default_factory=list)  # (cpu seconds, outcome, index), the 5 slowest
    bad: list = field(default_factory=list)  # (index, kind, dialect, outcome, detail, text)
    cli: list = field(default_factory=list)  # (index, dialect, outcome, text) for the console check
    peak_rss_mb: float = 0.0


def run_batch(task: Task, progress=None) -> BatchResult:
    """Run a task's programs in this process (``progress.value``: the index being run, for the parent's
    backstop)."""
    result = BatchResult()
    for index in range(task.start, task.start + task.count):
        if progress is not None:
            progress.value = index
        kind, text = program_at(task.seed, index, task.mix)
        dialect = task.dialects[index % len(task.dialects)]
        outcome, cpu, detail = _classify(text, task.time_limit, dialect)
        result.done += 1
        result.outcomes[(dialect, kind, outcome)] += 1
        if len(result.slowest) < 5 or cpu > result.slowest[-1][0]:
            result.slowest = sorted([*result.slowest, (round(cpu, 3), outcome, index)], reverse=True)[:5]
        if outcome.startswith(BAD_PREFIXES):
            result.bad.append((index, kind, dialect, outcome, detail, text))
        elif task.cli_every and index % task.cli_every == 0 and outcome != "error:time-budget":
            result.cli.append((index, dialect, outcome, text))
        if outcome == "over-memory":
            break  # a fresh worker: the failed allocation may have left the heap fragmented
    result.peak_rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return result


def _worker(conn, progress, memory_limit_mb: float) -> None:
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
            task = conn.recv()
        except EOFError:
            return
        if task is None:
            return
        conn.send(run_batch(task, progress))


class _Worker:
    """One forked worker process that runs tasks; restarted after a kill or a memory failure."""

    def __init__(self, memory_limit_mb: float) -> None:
        self.memory_limit_mb = memory_limit_mb
        self.process: multiprocessing.process.BaseProcess | None = None
        self.conn: Any = None  # multiprocessing.connection.Connection
        self.progress: Any = None  # multiprocessing.Value: the index being run
        self.task: Task | None = None
        self.watch: tuple[int, float | None] = (-1, None)  # (index seen, worker CPU seconds then)

    def start(self) -> None:
        context = multiprocessing.get_context("fork")
        self.conn, child = context.Pipe()
        self.progress = context.Value("q", -1, lock=False)
        self.process = context.Process(target=_worker, args=(child, self.progress, self.memory_limit_mb),
                                       daemon=True)  # fmt: skip
        self.process.start()
        child.close()

    def stop(self) -> None:
        if self.process is not None:
            self.process.kill()
            self.process.join()
            self.conn.close()
            self.process = None

    def submit(self, task: Task) -> None:
        if self.process is None:
            self.start()
        self.task = task
        self.watch = (-1, None)
        self.conn.send(task)

    def stuck(self, cpu_limit: float) -> tuple[str, int] | None:
        """The backstop, between answers: (outcome, index) when the worker died, or has spent more than
        ``cpu_limit`` CPU seconds (read from /proc: wall time on a loaded machine says little) on one
        program (the CPU alarm runs only between Python bytecodes, so a long C call escapes it)."""
        process = self.process
        assert process is not None
        index = int(self.progress.value)
        if not process.is_alive():
            return "over-memory", index
        cpu = _cpu_seconds(process.pid)
        seen, since = self.watch
        if index != seen or since is None:
            self.watch = (index, cpu)
            return None
        if cpu is not None and cpu - since > cpu_limit:
            return "over-time", index
        return None


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
    by_dialect_class: Counter = field(default_factory=Counter)  # (dialect, class) → programs
    by_kind_class: Counter = field(default_factory=Counter)  # (kind, class) → programs
    cli_checked: int = 0
    slowest: list = field(default_factory=list)  # (cpu seconds, outcome, index), the 5 slowest
    peak_rss_mb: float = 0.0
    seconds: float = 0.0
    cpu_seconds: float = 0.0  # the workers' CPU time
    bad: list = field(default_factory=list)  # (index, kind, outcome, detail, text); detail names the dialect

    def add(self, dialect: str, kind: str, outcome: str, n: int = 1) -> None:
        self.tried += n
        self.by_kind[kind] += n
        self.by_dialect[dialect] += n
        self.outcomes[outcome] += n
        self.by_dialect_class[(dialect, outcome.split(":")[0])] += n
        self.by_kind_class[(kind, outcome.split(":")[0])] += n

    def classes(self) -> dict[str, int]:
        """Outcome classes (ok / error / crash / over-time / over-memory / cli-mismatch) and counts."""
        out: Counter = Counter()
        for outcome, n in self.outcomes.items():
            out[outcome.split(":")[0]] += n
        return dict(out)

    def as_dict(self) -> dict:
        def nested(counter: Counter) -> dict:
            table: dict[str, dict[str, int]] = {}
            for (outer, inner), n in sorted(counter.items()):
                table.setdefault(outer, {})[inner] = n
            return table

        return {
            "seed": self.seed,
            "programs": self.tried,
            "by_kind": dict(self.by_kind),
            "by_dialect": dict(self.by_dialect),
            "classes": self.classes(),
            "by_dialect_class": nested(self.by_dialect_class),
            "by_kind_class": nested(self.by_kind_class),
            "outcomes": dict(self.outcomes.most_common()),
            "cli_checked": self.cli_checked,
            "slowest": self.slowest,
            "peak_rss_mb": round(self.peak_rss_mb),
            "seconds": round(self.seconds, 1),
            "cpu_seconds": round(self.cpu_seconds, 1),
            "bad": [{"index": i, "kind": k, "outcome": o, "detail": d} for i, k, o, d, _ in self.bad],
        }


def fuzz(
    *,
    seed: int = 0,
    programs_budget: int | None = 1000,
    seconds: float | None = None,
    time_limit: float = 4.0,
    memory_limit_mb: float = 2048.0,
    cli_every: int = 500,
    save: Path | None = None,
    progress: bool = False,
    dialects: Sequence[str] = ("gsk25i",),
    mix: dict[str, float] | None = None,
    workers: int = 1,
    batch: int = 250,
) -> Report:
    """Run the fuzzer until ``programs_budget`` programs or ``seconds`` (whichever first), in ``workers``
    forked processes that each run batches of ``batch`` programs in-process and send back counts. Program
    ``i`` is :func:`program_at` ``(seed, i, mix)`` and runs under ``dialects[i % len(dialects)]`` (the
    grammar is the Fanuc family's: in another language family most programs are errors, which still checks
    that every outcome is one clean line)."""
    weights = dict(mix or DEFAULT_MIX)
    dialect_list = tuple(dialects)
    report = Report(seed=seed)
    pool = [_Worker(memory_limit_mb) for _ in range(max(1, workers))]
    cpu_limit = 2 * time_limit + 10
    started = time.monotonic()
    pending: list[tuple[int, int]] = []  # (start, count) handed back after a worker was killed
    next_start = 0
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=programs_budget, unit="program", disable=None, file=sys.stderr, smoothing=0.05)

    def next_task() -> Task | None:
        nonlocal next_start
        if pending:
            start, count = pending.pop()
        else:
            if seconds is not None and time.monotonic() - started >= seconds:
                return None
            left = None if programs_budget is None else programs_budget - next_start
            if left is not None and left <= 0:
                return None
            start, count = next_start, batch if left is None else min(batch, left)
            next_start += count
        return Task(seed, start, count, dialect_list, weights, time_limit, cli_every)

    def record_bad(index: int, kind: str, dialect: str, outcome: str, detail: str, text: str) -> None:
        report.bad.append((index, kind, outcome, f"[{dialect}] {detail}", text))
        if save is not None:
            _save(save, index, dialect, outcome, detail, text)

    def merge(worker: _Worker, result: BatchResult) -> None:
        task = worker.task
        assert task is not None
        for (dialect, kind, outcome), n in result.outcomes.items():
            report.add(dialect, kind, outcome, n)
        report.slowest = sorted([*report.slowest, *result.slowest], reverse=True)[:5]
        report.peak_rss_mb = max(report.peak_rss_mb, result.peak_rss_mb)
        for index, kind, dialect, outcome, detail, text in result.bad:
            record_bad(index, kind, dialect, outcome, detail, text)
        for index, dialect, outcome, text in result.cli:
            report.cli_checked += 1
            problem = check_cli(text, outcome, time_limit, dialect)
            if problem:
                kind = program_at(seed, index, weights)[0]
                report.outcomes[outcome] -= 1
                report.outcomes["cli-mismatch"] += 1
                report.by_dialect_class[(dialect, outcome.split(":")[0])] -= 1
                report.by_dialect_class[(dialect, "cli-mismatch")] += 1
                report.by_kind_class[(kind, outcome.split(":")[0])] -= 1
                report.by_kind_class[(kind, "cli-mismatch")] += 1
                record_bad(index, kind, dialect, "cli-mismatch", problem, text)
        if result.done < task.count:  # stopped after a memory failure: the rest goes to a fresh worker
            worker.stop()
            pending.append((task.start + result.done, task.count - result.done))
        if bar is not None:
            bar.update(result.done)
            bar.set_postfix(bad=len(report.bad))

    def kill(worker: _Worker, outcome: str, index: int) -> None:
        task = worker.task
        assert task is not None
        cpu = _cpu_seconds(worker.process.pid if worker.process else None) or 0.0
        report.cpu_seconds += cpu
        worker.stop()
        kind, text = program_at(seed, index, weights)
        dialect = dialect_list[index % len(dialect_list)]
        # The programs before it ran, but their counts died with the worker: run them again elsewhere.
        if index > task.start:
            pending.append((task.start, index - task.start))
        if task.start + task.count > index + 1:
            pending.append((index + 1, task.start + task.count - index - 1))
        report.add(dialect, kind, outcome)
        detail = "killed by the backstop: no answer" if outcome == "over-time" else "worker died"
        record_bad(index, kind, dialect, outcome, detail, text)
        if bar is not None:
            bar.update(1)

    from multiprocessing.connection import wait

    try:
        busy: dict[Any, _Worker] = {}
        idle = list(pool)
        while True:
            while idle:
                task = next_task()
                if task is None:
                    break
                worker = idle.pop()
                worker.submit(task)
                busy[worker.conn] = worker
            if not busy:
                break
            for conn in wait(list(busy), timeout=1.0):
                worker = busy.pop(conn)
                try:
                    result = conn.recv()
                except EOFError:
                    busy[conn] = worker  # died: the backstop below names the program
                    continue
                merge(worker, result)
                idle.append(worker)
            for conn, worker in list(busy.items()):
                stuck = worker.stuck(cpu_limit)
                if stuck is not None:
                    del busy[conn]
                    kill(worker, *stuck)
                    idle.append(worker)
    finally:
        for worker in pool:
            if worker.process is not None:
                report.cpu_seconds += _cpu_seconds(worker.process.pid) or 0.0
            worker.stop()
        if bar is not None:
            bar.close()
    report.seconds = time.monotonic() - started
    return report


def _save(folder: Path, index: int, dialect: str, outcome: str, detail: str, text: str) -> None:
    where = folder / outcome.replace(":", "-")
    where.mkdir(parents=True, exist_ok=True)
    (where / f"{index:07d}-{dialect}.nc").write_bytes(text.encode("utf-8", "surrogatepass"))
    (where / f"{index:07d}-{dialect}.txt").write_text(detail + "\n")


def _parse_mix(text: str) -> dict[str, float]:
    mix: dict[str, float] = {}
    for part in text.split(","):
        name, _, weight = part.partition("=")
        if name not in DEFAULT_MIX:
            raise ValueError(f"unknown program kind {name!r} (choose from {', '.join(DEFAULT_MIX)})")
        mix[name] = float(weight) if weight else 1.0
    if not any(w > 0 for w in mix.values()):
        raise ValueError("at least one program kind needs a positive weight")
    return mix


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--programs", type=int, default=None, help="programs to try (default 10000 without --seconds)"
    )
    parser.add_argument("--seconds", type=float, default=None, help="wall-clock budget in seconds")
    parser.add_argument("--time-limit", type=float, default=4.0, help="CPU seconds one program may take (4)")
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
    parser.add_argument(
        "--mix",
        default=",".join(f"{k}={v:g}" for k, v in DEFAULT_MIX.items()),
        help="program kinds and weights (default %(default)s)",
    )
    parser.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument("--batch", type=int, default=250, help="programs per task sent to a worker (250)")
    args = parser.parse_args(argv)
    from cnc_gym.gcode import DIALECT_MODULES

    built = sorted(name for name, module in DIALECT_MODULES.items() if module)
    dialects = built if args.dialect == "all" else args.dialect.split(",")
    unknown = [name for name in dialects if name not in built]
    if unknown:
        parser.error(f"unknown dialect {unknown[0]!r}: choose from {', '.join(built)} or all")
    try:
        mix = _parse_mix(args.mix)
    except ValueError as exc:
        parser.error(str(exc))
    if args.workers < 1 or args.batch < 1:
        parser.error("--workers and --batch are at least 1")
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
        mix=mix,
        workers=args.workers,
        batch=args.batch,
    )
    if args.json:
        print(json.dumps(report.as_dict()))
    else:
        print(
            f"seed {report.seed}: {report.tried} programs in {report.seconds:.0f} s "
            f"({report.cpu_seconds:.0f} s worker CPU), "
            f"{report.cli_checked} also through `cnc-gym trace`; worker peak RSS {report.peak_rss_mb:.0f} MiB"
        )
        classes = sorted(report.classes(), key=lambda c: (c not in ("ok", "error"), c))
        print(f"  {'':<12}" + "".join(f"{c:>14}" for c in classes) + f"{'total':>10}")
        for title, table, keys in (("dialect", report.by_dialect_class, sorted(report.by_dialect)),
                                   ("kind", report.by_kind_class, sorted(report.by_kind))):  # fmt: skip
            for key in keys:
                row = "".join(f"{table[(key, c)]:>14}" for c in classes)
                total = report.by_dialect[key] if title == "dialect" else report.by_kind[key]
                print(f"  {key:<12}{row}{total:>10}")
            print()
        for name, n in sorted(report.classes().items(), key=lambda kv: -kv[1]):
            print(f"  {name:<14} {n:>8}  {100 * n / max(report.tried, 1):6.2f} %")
        common = report.outcomes.most_common()
        codes = [f"{o.split(':', 1)[1]} {n}" for o, n in common if o.startswith("error:")]
        print(f"  error codes ({len(codes)}): " + ", ".join(codes))
        print(
            "  slowest (CPU s, outcome, program #): "
            + ", ".join(f"{s:.2f} {o} #{i}" for s, o, i in report.slowest)
        )
        for index, kind, outcome, detail, _ in report.bad[:30]:
            print(f"  BAD #{index} ({kind}) {outcome}: {detail}")
    return 1 if report.bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
