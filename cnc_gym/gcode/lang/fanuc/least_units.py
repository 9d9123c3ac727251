"""Least-input-unit literals (decimal-point mode DPI = 0) for the Fanuc family: a number without a decimal
point in a length address counts least input increments *of the unit in force when the block runs*.

On a Fanuc 0i-M with parameter 3401#0 DPI = 0 (IS-B) ``X1000`` is 1 mm in G21 and 0.1 inch in G20;
Syntec 8.20 reads ``X5500`` as 5.5 mm in G71 and 0.55 inch in G70. A dialect with
``Dialect.integer_is_unit = False`` uses :class:`LeastUnitReader` and :func:`evaluate` for it (the GSK
25i's standard DPI = 1 reads ``X10`` as 10 mm or 10 inch and needs neither).

* The reader cannot know the unit in force (a G20 may come later, from a subprogram, or from the power-on
  setting), so such a literal becomes the node ``("num", value at the metric increment, count)``: the
  family's evaluator reads it as a number, :func:`evaluate` as ``count`` least units of the unit in force
  (the step the core passes for length addresses). A block that selects its unit itself (G20/G21 run
  first in it) is read in that unit at once.
* A fraction finer than the metric increment (``X1.2345``, meant in inches) is kept whole,
  ``("num", value)``, and rounded to the least increment in force when the block runs (the core's rule
  for a length from an expression), instead of being cut at the metric increment while it is read.
* Zero (``X0``) means the same in every unit and stays a plain number, so ``G00 X0 Y0`` keeps the fast
  path.
* Counts that are not lengths although their address is one (the repeat count ``K2``, ``G04 X1500``
  = 1.5 s) read the literal's digits: :func:`whole_count`, :func:`is_whole`.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from cnc_gym.gcode.codes import round_to
from cnc_gym.gcode.lang.fanuc.expressions import evaluate as family_evaluate
from cnc_gym.gcode.lang.fanuc.reader import Reader

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect, Seam
    from cnc_gym.gcode.program import Block, Program


class _Rescan(Exception):
    """A plain block holds a literal that needs a node: read it with the scanner instead."""


def least_units(node: tuple) -> int | None:
    """The count of least input units of an integer length literal's node, else None."""
    return node[2] if len(node) == 3 and node[0] == "num" else None


def evaluate(node: tuple, variables, dialect: Dialect, round_step: float | None = None) -> float | None:
    """The family's evaluator, with integer length literals read in the least unit in force
    (``round_step``, the unit the core passes for length addresses); without a step (a plain-number use,
    a G06.2 knot ``K1``) the count itself."""
    if node[0] == "num" and len(node) == 3:
        return node[2] * round_step if round_step else float(node[2])
    return family_evaluate(node, variables, dialect, round_step)


def word_node(core: Seam, letter: str):
    """The block's word ``letter`` as read: ``(value or node, text or None)``, or None when absent."""
    for word in core.state.block_words:
        if word[0] == letter:
            return word[1], word[-1]
    return None


def is_whole(core: Seam, letter: str) -> bool:
    """Whether the block's ``letter`` word is a literal without a decimal point."""
    found = word_node(core, letter)
    if found is None:
        return False
    value, text = found
    if text is not None:
        return "." not in text
    return isinstance(value, tuple) and least_units(value) is not None


def whole_count(core: Seam, letter: str, value: float) -> float:
    """A literal without a decimal point as its digits (``X2500`` → 2500, whatever the unit in force);
    ``value`` otherwise."""
    found = word_node(core, letter)
    if found is not None:
        node, text = found
        if text is not None and "." not in text:
            return float(text)
        if isinstance(node, tuple) and least_units(node) is not None:
            return float(least_units(node))  # type: ignore[arg-type]
    return value


def integer_words_hint(core: Seam, letters: str) -> str:
    """For an arc error where numbers without a decimal point are least units and the dialect has the
    calculator-type setting: which of the arc block's and the start point's block's ``letters`` words have
    no decimal point (``; X26 at line 12, which set the start point, has no decimal point …``), else ""."""
    dialect = core.dialect
    runner = core.state.flow
    if dialect.integer_is_unit or not dialect.calculator_input_parameter or runner is None:
        return ""
    unit = runner.frames[-1].unit
    here = core.state.out.line
    start = core.state.builder.last_source()
    found: list[str] = []
    example = ""
    for what, line in (("the end point", here), ("the start point", start[1] if start else None)):
        if line is None:
            continue
        block = next((b for b in unit.blocks[unit.start : unit.end] if b.line == line), None)
        words: list[tuple[str, int]] = []
        for word in block.words if block is not None else ():
            count = least_units(word[1]) if word[0] in letters and isinstance(word[1], tuple) else None
            if count:
                words.append((word[0], count))
        if words:
            found.append(f"{' '.join(f'{a}{n}' for a, n in words)} at line {line} ({what})")
            letter, count = words[0]
            example = example or f"{letter}{count} is {count * core.state.increment:g} mm"
    if not found:
        return ""
    return (f"; {' and '.join(found)} without a decimal point: least input increments "
            f"({dialect.calculator_input_parameter} = 0: {example}); if they mean mm, trace with "
            "--calculator-input")


def _unit_code_pattern(dialect: Dialect) -> re.Pattern[str] | None:
    """The dialect's inch/metric codes (G20/G21, Syntec's G70/G71) in a block's text, as the code itself
    (not G200 or G20.1); group 1 is the inch code's number when it matched."""
    roles = dialect.roles
    if roles.inch is None or roles.metric is None or roles.inch % 10 or roles.metric % 10:
        return None
    return re.compile(rf"G0*(?:({roles.inch // 10})|{roles.metric // 10})(?![0-9.])")


class LeastUnitReader(Reader):
    """The Fanuc family's reader with least-unit literals (module docstring). With ``integer_is_unit`` (the
    dialect's calculator-type input, :func:`~cnc_gym.gcode.dialect.calculator_input`) it reads numbers as
    the family's reader does.

    Where the dialect has a calculator-type input setting and the program reads in least units, a program
    whose coordinates of one axis come both with and without a decimal point gets a warning (``X10`` next
    to ``X10.5`` is 0.01 mm next to 10.5 mm: usually a program written for the other setting)."""

    def __init__(self, dialect: Dialect, macro_calls=None) -> None:
        super().__init__(dialect, macro_calls)
        self._mode = "off"  # "plain": a plain block is being read; "scan": an ordinary block is scanned
        self._unit: float | None = None  # the least unit of a block that holds its own G20/G21
        self._unit_code = _unit_code_pattern(dialect)
        self._watch = not dialect.integer_is_unit and bool(dialect.calculator_input_parameter)
        self._axes = frozenset(dialect.axes)
        self._with_point: set[str] = set()  # axes with a literal that has a decimal point
        self._without_point: dict[str, tuple[int, str]] = {}  # axis → (line, digits) of its first integer

    def read(self, text: str, file: str = "<program>") -> Program:
        self._with_point, self._without_point = set(), {}
        program = super().read(text, file)
        mixed = [a for a in self.dialect.axes if a in self._with_point and a in self._without_point]
        if mixed:
            axis = mixed[0]
            line, digits = self._without_point[axis]
            count = int(digits)
            mm = count * self.dialect.least_increment_mm
            program.notices.append((line, "warning", (
                f"{axis}{digits} has no decimal point and reads {mm:g} mm ({count} least input increments, "
                f"{self.dialect.calculator_input_parameter} = 0), while other {axis} words have one: if the "
                f"program means {axis}{count}. ({count} mm), trace it with --calculator-input (the machine "
                "preset's calculator_input)"), "mixed-decimal-point"))  # fmt: skip
        return program

    def _note_format(self, letter: str, digits: str | None, line: int) -> None:
        """Whether an axis word is written with a decimal point (the mixed-format warning)."""
        if not self._watch or digits is None or letter not in self._axes:
            return
        if "." in digits:
            self._with_point.add(letter)
        elif digits.strip("+-0") and letter not in self._without_point:
            self._without_point[letter] = (line, digits.lstrip("+"))

    def _plain_value(self, pair: tuple[str, str], text: str, line: int) -> float | None:
        if self._watch and not self._mentions_call(text):  # (a macro call's words are arguments)
            self._note_format(pair[0], pair[1], line)
        return super()._plain_value(pair, text, line)

    def _plain_block(self, text: str, line: int) -> Block:
        self._mode = "plain"
        try:
            return super()._plain_block(text, line)
        except _Rescan:
            return self._scan_block(text, line)  # type: ignore[return-value]  # a plain block is never empty
        finally:
            self._mode = "off"

    def _scan(self, text: str, line: int, relaxed: bool, code_rules: dict | None = None, *,
              defer: bool = False) -> Block | None:  # fmt: skip
        # Macro-call arguments (relaxed) keep the family's reading: a number at the metric least unit. A
        # block that selects its unit itself (G20/G21 run first) is read in that unit at once.
        saved, self._mode = self._mode, "off" if relaxed else "scan"
        unit = self._unit_code.search(text) if self._unit_code is not None else None
        self._unit = None if unit is None else (self.dialect.least_increment_inch if unit.group(1)
                                                else self.dialect.least_increment_mm)  # fmt: skip
        try:
            return super()._scan(text, line, relaxed, code_rules, defer=defer)
        finally:
            self._mode = saved
            self._unit = None

    def _value(self, letter: str, text: str, pos: int, line: int, rule: tuple):
        value, digits, end = super()._value(letter, text, pos, line, rule)
        if self._mode == "scan":
            self._note_format(letter, digits, line)
        if digits is not None and isinstance(value, tuple):
            return value, None, end  # a node: evaluated when the block runs, in the unit in force
        return value, digits, end

    def _literal(self, letter: str, digits: str, rule: tuple, line: int):
        _, _, point_allowed, is_length = rule
        if is_length and self._mode != "off" and not self.dialect.integer_is_unit:
            point = digits.find(".")
            whole = point < 0
            finer = point_allowed and len(digits) - point - 1 > self._decimals
            if (whole and digits.strip("+-0")) or (not whole and finer):
                if self._mode == "plain":
                    raise _Rescan
                value = super()._literal(letter, digits[:point + 1 + self._decimals] if not whole else digits,
                                         rule, line)  # the range and sign checks, at the metric unit
                if self._unit is not None:  # the block's own G20/G21: its unit is known
                    return int(digits) * self._unit if whole else round_to(float(digits), self._unit)
                return ("num", value, int(digits)) if whole else ("num", float(digits))
        return super()._literal(letter, digits, rule, line)
