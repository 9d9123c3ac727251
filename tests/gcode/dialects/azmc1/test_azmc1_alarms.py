"""Every error condition of the AMK AZ-MC1 programming manual (docs/azmc1_alarms.md, A1-A22) as a minimal
program that raises it with our code at the line of the offending block. The manual numbers no alarm, so
no error carries an alarm number. ``CASES`` is read by tests/gcode/test_dialect_alarm_indexes.py to check
the index's "Our code" column.
"""

from __future__ import annotations

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret

#: Row → [(program, code, alarm, line)].
CASES: dict[str, list[tuple[str, str, int | None, int]]] = {
    "A1": [("G1 F100\nX50R1=7\n", "syntax", None, 2)],
    "A2": [("G1 F100 U5\n", "unsupported-axis", None, 1), ("G1 F100\nX\n", "syntax", None, 2)],
    "A3": [("R1 = 2\n$IF R1 >= -5\n$ENDIF\n", "syntax", None, 2), ("R1 = 2 * -3\n", "syntax", None, 1)],
    "A4": [("R1 = 1\n$WHILE R1 G1 X1\n$ENDWHILE\n", "syntax", None, 2),
           ("G1 X1 $TIME 2\n", "syntax", None, 1)],
    "A5": [("$ WHILE 1\n", "syntax", None, 1)],
    "A7": [("G1 F100 X214000.0001\n", "value-out-of-range", None, 1),
           ("R1 = 300000\nG1 F100 X R1\n", "value-out-of-range", None, 2)],
    "A8": [("R1 = LN[0]\n", "math-error", None, 1), ("R1 = SQRT[-2]\n", "math-error", None, 1),
           ("R1 = ACOS[1.1]\n", "math-error", None, 1), ("R1 = TAN[90]\n", "math-error", None, 1),
           ("R1 = 5 / [2 - 2]\n", "math-error", None, 1)],
    "A9": [("G0 X10\nG2 X0 Y8 I-10 F100\n", "arc-radius-mismatch", None, 2)],
    "A10": [("G74 X1 M3\n", "bad-combination", None, 1)],
    "A11": [("G99 X100\nG0 X50\nG1 X100.001 F100\n", "soft-limit", None, 3),
            ("G98 Z-10\nG0 Z-10.5\n", "soft-limit", None, 2)],
    "A12": [("M18 S200\n", "not-implemented", None, 1)],
    "A14": [("D1\nG41\nG2 X10 I5 F100\n", "comp-arc-startup", None, 3)],
    "A15": [("D1\nG41 G1 X10 F100\nG42 X20\n", "tro-direct-change", None, 3)],
    "A16": [("D1\nG41 G1 X10 F100\nX20\nG40\n", "tro-deselect-no-travel", None, 4),
            ("D1\nG41 G1 X10 F100\nX20\nG40 G2 X30 I5\n", "comp-arc-startup", None, 4)],
    "A17": [("G0 X-20 D1\nG41 G1 X-10 Y0 F100\nX10\nG3 X20 Y0 I5 J0\nG1 X30\nG40 X40\n",
             "comp-interference", None, 4)],
    "A19": [("%L1\nLL2\nM29\n%L2\nM29\n%1\nLL1\n", "bad-call", None, 2),
            ("LL7\n", "program-not-found", None, 1), ("L7\n", "program-not-found", None, 1)],
    "A20": [("M29\n", "bad-subroutine-end", None, 1)],
    "A21": [("$IF 1\nG0 X1\n", "control-structure", None, 1), ("$ENDWHILE\n", "control-structure", None, 1),
            ("$BREAK\n", "control-structure", None, 1),
            ("$FOR R1 = 1, 2, 1\n$CONTINUE\n$ENDWHILE\n", "control-structure", None, 3)],
    "A22": [("$WHILE 1\n$ENDWHILE\n", "too-many-blocks", None, 1)],  # the block the count runs out at
}


@pytest.mark.parametrize(("row", "index"),
                         [(row, k) for row, cases in CASES.items() for k in range(len(cases))])  # fmt: skip
def test_manual_alarm(row: str, index: int) -> None:
    text, code, alarm, line = CASES[row][index]
    with pytest.raises(ProgramError) as info:
        interpret(text, dialect="azmc1", file="case.din", max_blocks=1000, tool_offsets={"D": {1: 6.0}})
    err = info.value
    assert (err.code, err.alarm) == (code, alarm), (row, str(err))
    assert err.file == "case.din" and err.line == line, (row, str(err))
