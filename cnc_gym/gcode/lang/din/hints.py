"""Hints for syntax errors that come from another G-code language (the DIN family's
:attr:`Language.hint <cnc_gym.gcode.dialect.Language.hint>`).

A Fanuc-style program read as DIN fails on its first ``#``, ``O`` number or macro statement. When the line
looks like that, the one-line error says what it probably is and how DIN writes it:

* ``#1 = 5``, ``X#1`` — a Fanuc macro variable: DIN parameters are ``R1 = 5``, ``X R1``;
* ``O1234`` — a Fanuc program number: a DIN program starts with ``%1234`` (a file is a program);
* ``IF [...] GOTO``, ``WHILE [...] DO1`` — Fanuc macro statements: DIN has ``$IF``/``$WHILE`` blocks and
  no GOTO;
* ``G02 … R5`` — an arc radius: DIN arcs take the centre I/J/K; R is a parameter;
* ``; comment`` — a ';' comment: DIN comments are ``( … )``.
"""

from __future__ import annotations

import re

_MACRO_VARIABLE = re.compile(r"#\s*[\d\[]")
_PROGRAM_NUMBER = re.compile(r"^\s*(?:N\d+\s*)?O\s*\d", re.IGNORECASE)
_MACRO_STATEMENT = re.compile(r"\b(?:GOTO\s*\d|IF\s*\[|WHILE\s*\[|END\s*\d)", re.IGNORECASE)
_ARC_RADIUS = re.compile(r"\bG0?[23]\b.*\bR\s*[-+]?[\d.]", re.IGNORECASE)


def hint(line: str) -> str | None:
    """A hint for a line that failed to read, or None when it does not look like another language."""
    if _MACRO_STATEMENT.search(line):
        return "a Fanuc macro statement? DIN has $IF … $ENDIF and $WHILE … $ENDWHILE blocks, and no GOTO"
    if _MACRO_VARIABLE.search(line):
        return "a Fanuc macro variable? DIN parameters are R<n>: R1 = 5, X R1"
    if _PROGRAM_NUMBER.search(line):
        return "a Fanuc program number? a DIN program starts with %<number>; the file is the program"
    if _ARC_RADIUS.search(line):
        return ("an arc radius R? DIN arcs take the centre I/J/K (G162 relative, G161 absolute); R is a "
                "parameter")
    if ";" in line:
        return "a ';' comment? DIN comments are ( … )"
    return None
