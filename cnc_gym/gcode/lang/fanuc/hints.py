"""Hints for syntax errors that come from another G-code language (the Fanuc family's
:attr:`Language.hint <cnc_gym.gcode.dialect.Language.hint>`).

Programs written for LinuxCNC, or copied from a controller that abbreviates its macro keywords, fail on
a Fanuc-family controller with an error that names the first character it could not read. When the line
looks like such syntax, the one-line error says what it probably is and how this language writes it:

* ``; comment`` — a ';' comment (LinuxCNC, many CAM posts): here ';' ends a block, comments are ``( … )``
  (the reader gives this one, when the part after a ';' is what fails, :data:`SEMICOLON_COMMENT`);
* ``o100 sub`` / ``O200 call`` / ``o101 if`` — a LinuxCNC O-word: here subprograms are ``O`` programs
  called with M98 (G65 with arguments) and loops are ``WHILE[…]DOn … ENDn``;
* ``#<depth>`` — a LinuxCNC named parameter: here variables are numbered;
* ``WH[…]`` — an abbreviated macro keyword (``WH`` for WHILE): write the keyword in full;
* ``%123`` — a DIN-style program start: here ``%`` is the tape mark and programs are ``O`` numbers.
"""

from __future__ import annotations

import re

_O_WORD = re.compile(r"^\s*(?:/\d?\s*)?(?:N\d+\s*)?O\s*(?:\d+|<[^>]*>)\s*"
                     r"(SUB|ENDSUB|CALL|IF|ELSEIF|ELSE|ENDIF|WHILE|ENDWHILE|DO|REPEAT|ENDREPEAT|RETURN|BREAK|"
                     r"CONTINUE)\b", re.IGNORECASE)  # fmt: skip
_NAMED_PARAMETER = re.compile(r"#\s*<")
#: The hint for a ';' comment (the reader gives it when the part after a ';' is what fails to read).
SEMICOLON_COMMENT = "a ';' comment? in this dialect ';' ends a block; comments go in parentheses ( … )"
_PERCENT_PROGRAM = re.compile(r"^\s*%\s*\d")
_ABBREVIATED = re.compile(r"(?<![A-Z])WH\s*\[", re.IGNORECASE)


def hint(line: str) -> str | None:
    """A hint for a line that failed to read, or None when it does not look like another language."""
    if _O_WORD.search(line):
        return ("a LinuxCNC O-word? this dialect calls subprograms with M98 P_ (G65 P_ with arguments) and "
                "loops with WHILE[…]DOn … ENDn")  # fmt: skip
    if _NAMED_PARAMETER.search(line):
        return ("a LinuxCNC named parameter? this dialect's variables are numbered: #1-#33 local, "
                "#100-#999 common")
    if _PERCENT_PROGRAM.search(line):
        return "a program number after '%'? '%' is the tape mark alone on its line; programs are O<number>"
    if _ABBREVIATED.search(line):
        return "an abbreviated macro keyword? write WHILE[…]DOn in full"
    return None
