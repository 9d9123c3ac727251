"""Syntec 8.20's lexical rules on the Fanuc family's reader (Syntec 8.20 mill programming manual §1.1,
§G04, §G70/G71 and the examples throughout):

* ``//`` starts a comment to the end of the line, outside ``( … )`` (``G05 P10000 //Start high speed``);
  ``( … )`` comments and ``;`` as the end of a block are the family's;
* a number without a decimal point in a length address (X Y Z I J K R Q E) is a count of least input
  units, and the unit is the one in force when the block runs: 0.001 mm in G71, 0.0001 inch in G70
  (``X5500`` is 5.5 mm, ``G02 I1000`` a 1 mm radius). The reader cannot know the unit in force (a G70
  may come later, or from the power-on setting), so such a literal becomes the node ``("num", value at
  0.001, count)``: the family's evaluator reads it as a number, and :func:`evaluate` as ``count`` least
  units of the unit in force. A literal finer than 0.001 is kept whole (``("num", value)``) and rounded
  to the least unit in force when the block runs. F, P, K as a count, S, T, H, D, L, N keep their own
  rules (F1000 is 1000 mm/min).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.codes import round_to
from cnc_gym.gcode.lang.fanuc.expressions import evaluate as family_evaluate
from cnc_gym.gcode.lang.fanuc.reader import Reader

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect
    from cnc_gym.gcode.program import Block, Program


#: G70 / G71 in a block's text (the code, not G700 or G70.1).
_UNIT_CODE = re.compile(r"G0*7([01])(?![0-9.])")


class _Rescan(Exception):
    """A plain block holds a literal that needs a node: read it with the scanner instead."""


def strip_line_comment(line: str) -> str:
    """The line without its ``//`` comment (a ``//`` inside ``( … )`` is part of that comment)."""
    start = line.find("//")
    if start < 0:
        return line
    if "(" not in line[:start]:
        return line[:start]
    inside = False
    for index, c in enumerate(line):
        if c == "(":
            inside = True
        elif c == ")":
            inside = False
        elif c == "/" and not inside and line.startswith("//", index):
            return line[:index]
    return line


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


class SyntecReader(Reader):
    """The Fanuc family's reader with ``//`` comments and least-unit literals (module docstring)."""

    def __init__(self, dialect: Dialect, macro_calls=None) -> None:
        super().__init__(dialect, macro_calls)
        self._mode = "off"  # "plain": a plain block is being read; "scan": an ordinary block is scanned
        self._unit: float | None = None  # the least unit of a block that holds G70/G71

    def read(self, text: str, file: str = "<program>") -> Program:
        if "//" in text:
            text = "\n".join(strip_line_comment(line) for line in text.splitlines())
        try:
            return super().read(text, file)
        except ProgramError as err:
            err.alarm = self.dialect.alarms.get(err.code)  # Syntec's numbers, not the family's
            raise

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
        # block that selects its unit itself (G70/G71 run first) is read in that unit at once.
        saved, self._mode = self._mode, "off" if relaxed else "scan"
        unit = _UNIT_CODE.search(text)
        self._unit = None if unit is None else (self.dialect.least_increment_inch if unit.group(1) == "0"
                                                else self.dialect.least_increment_mm)  # fmt: skip
        try:
            return super()._scan(text, line, relaxed, code_rules, defer=defer)
        finally:
            self._mode = saved
            self._unit = None

    def _value(self, letter: str, text: str, pos: int, line: int, rule: tuple):
        value, digits, end = super()._value(letter, text, pos, line, rule)
        if digits is not None and isinstance(value, tuple):
            return value, None, end  # a node: evaluated when the block runs, in the unit in force
        return value, digits, end

    def _literal(self, letter: str, digits: str, rule: tuple, line: int):
        _, _, point_allowed, is_length = rule
        if is_length and self._mode != "off":
            point = digits.find(".")
            whole = point < 0
            if whole or (point_allowed and len(digits) - point - 1 > self._decimals):
                if self._mode == "plain":
                    raise _Rescan
                value = super()._literal(letter, digits[:point + 1 + self._decimals] if not whole else digits,
                                         rule, line)  # the range and sign checks, at the metric unit
                if self._unit is not None:  # the block's own G70/G71: its unit is known
                    return int(digits) * self._unit if whole else round_to(float(digits), self._unit)
                return ("num", value, int(digits)) if whole else ("num", float(digits))
        return super()._literal(letter, digits, rule, line)
