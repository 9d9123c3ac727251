"""Syntec 8.20's lexical rules on the Fanuc family's reader (Syntec 8.20 mill programming manual §1.1,
§G04, §G70/G71 and the examples throughout):

* ``//`` starts a comment to the end of the line, outside ``( … )`` (``G05 P10000 //Start high speed``);
  ``( … )`` comments and ``;`` as the end of a block are the family's;
* a number without a decimal point in a length address (X Y Z I J K R Q E) is a count of least input
  units, and the unit is the one in force when the block runs: 0.001 mm in G71, 0.0001 inch in G70
  (``X5500`` is 5.5 mm, ``G02 I1000`` a 1 mm radius): the family's least-unit reading
  (``lang/fanuc/least_units.py``, shared with ``fanuc``). F, P, K as a count, S, T, H, D, L, N keep their
  own rules (F1000 is 1000 mm/min).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.lang.fanuc.least_units import LeastUnitReader

if TYPE_CHECKING:
    from cnc_gym.gcode.program import Program


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


class SyntecReader(LeastUnitReader):
    """The family's least-unit reader with ``//`` comments and Syntec's alarm numbers."""

    def read(self, text: str, file: str = "<program>") -> Program:
        if "//" in text:
            text = "\n".join(strip_line_comment(line) for line in text.splitlines())
        try:
            return super().read(text, file)
        except ProgramError as err:
            err.alarm = self.dialect.alarms.get(err.code)  # Syntec's numbers, not the family's
            raise
