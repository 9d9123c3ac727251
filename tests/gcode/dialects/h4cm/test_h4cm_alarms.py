"""A minimal program per error condition of the HUST H4C-M manual (docs/h4cm_alarms.md lists them, A1-A33):
each ends in the error code and H4C-M error number (None where the manual numbers none) at the line of the
offending block. ``CASES`` is read by tests/gcode/test_dialect_alarm_indexes.py to check the index's
"Our code" and "Our alarm" columns.
"""

from __future__ import annotations

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret
from cnc_gym.machine import load_machine

COMP = "G41 D1 Y10. F100\n"

#: Index row → [(program, error code, H4C-M error number or None, line of the error[, interpret options])].
CASES: dict[str, list[tuple]] = {
    "A3": [("G10 P200 L1\nG01 X1. F100\nM99\n", "part-count-limit", 3, 3, {"main_m99": "restart"})],
    "A4": [("G60 X10. L2\n", "unknown-code", 13, 1)],
    "A5": [("G01 X1. F100\nN1 G01" + " " * 34 + "X1.000 Y2.000 Z3.000 F100\n", "block-too-long", 8, 2)],
    "A8": [("G73 X1. Y1. Z-1. R1. Q1. F100\n", "unknown-code", 13, 1),
           ("G84 X1. Y1. Z-1. R1. F100\n", "not-implemented", 13, 1),
           ("G08 X0\n", "not-implemented", 13, 1)],
    "A12": [("G91\nG00 X9000.\nX9000.\n", "travel-limit", 20, 3, {"machine": "h4cm"}),
            ("G91\nG00 Z-9000.\nZ-9000.\n", "travel-limit", 20, 3, {"machine": "h4cm"})],
    "A14": [("M98 P1\nM02\n" + "".join(f"O{n}\nM98 P{n + 1}\nM99\n" for n in range(1, 6)) + "O6\nM99\n",
             "nesting", 24, 16)],
    "A15": [("G02 X10. Y0 I3. F100\n", "arc-radius-mismatch", 25, 1),
            ("G02 X100. Y0 R10. F100\n", "arc-impossible", 25, 1),
            ("G02 X10. Y0 F100\n", "arc-missing-center", 25, 1)],
    "A16": [("G02 X10. Y10. R10. F100\nX0 Y20.\n", "arc-mode", 25, 2),
            ("G02 X10. Y10. R10. F100\nG03 X0 Y20. R10.\n", "arc-mode", 25, 2)],
    "A17": [("G03 X-20. Y0 R10. F100\n", "arc-r-sweep", 25, 1),
            ("G02 X0.5 Y0 R10. F100\n", "arc-r-sweep", 25, 1),
            ("G03 X0 Y0 R10. F100\n", "arc-r-sweep", 25, 1)],
    "A23": [("G65 L99 P1\n", "user-alarm", 51, 1), ("G65 L99 P49\n", "user-alarm", 99, 1),
            ("G65 L99 P50\n", "user-alarm", 50, 1)],
    "A24": [("G02 X10. Y10. R10. F100\nG41 D1 X12.\n", "comp-arc-startup", None, 2)],
    "A25": [(COMP + "G01 X10.\nG03 X14. Y14. J4.\nG01 Y30.\nG40 X0\n", "comp-interference", None, 3)],
    "A26": [(COMP + "G42 X20.\n", "comp-switch", None, 2)],
    "A27": [(COMP + "G01 X10. D2\n", "comp-d-change", None, 2)],
    "A28": [("G65 L04 P#1 A9999999 B10\n", "overflow", None, 1),
            ("G65 L01 P#1 A9999999\nG65 L02 P#1 A#1 B1\n", "overflow", None, 2)],
    "A29": [(COMP + "G28\n", "comp-not-cancelled", None, 2),
            (COMP + "G31 X5.\n", "comp-not-cancelled", None, 2),
            (COMP + "G81 X1. Y1. Z-5. R1.\n", "comp-not-cancelled", None, 2)],
    "A30": [("D17\n", "bad-offset-number", None, 1)],
    "A31": [("G91\nG22 X0 Y0 Z-1. R1. I5. J0 F100\n", "groove-absolute-only", None, 2)],
    "A32": [("G65 L08 P#1 A1\n", "unknown-code", 13, 1)],
    "A33": [("M98 P1000\n", "bad-call", None, 1)],
    "A34": [("M98 P1 X5.\nM30\nO1\nM99\n", "call-with-position", None, 1),
            ("G90\nM98 P1 U5.\nM30\nO1\nM99\n", "call-with-position", None, 2)],
}  # fmt: skip


@pytest.mark.parametrize(("row", "index"),
                         [(row, k) for row, cases in CASES.items() for k in range(len(cases))])  # fmt: skip
def test_manual_alarm(row: str, index: int) -> None:
    text, code, alarm, line, *options = CASES[row][index]
    options = [{k: load_machine(v) if k == "machine" else v for k, v in o.items()} for o in options]
    with pytest.raises(ProgramError) as info:
        interpret(text, dialect="h4cm", file="part.nc", tool_offsets={"D": {1: 5.0, 2: 3.0}},
                  **dict(*options))  # fmt: skip
    err = info.value
    assert (err.code, err.alarm, err.file, err.line) == (code, alarm, "part.nc", line), err
    assert str(err).startswith(f"part.nc:{line}: ") and str(err).endswith(f"[{code}]")
