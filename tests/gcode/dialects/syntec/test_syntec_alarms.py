"""A minimal program per error condition of the Syntec 8.20 mill programming manual (docs/syntec_alarms.md
lists them, A1-A28): each ends in the error code and Syntec alarm number (only the MAR alarms of G37/G37.1
have one) at the line of the offending block. ``CASES`` is read by tests/gcode/test_dialect_alarm_indexes.py
to check the index's "Our code" and "Our alarm" columns.
"""

from __future__ import annotations

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret

#: The simulated tool-length instrument of the G37/G37.1 cases: H1's probe fires at Z-10.
PROBE = {"signal_at": {1: -10.0}}
CYCLE = "F100 S500 M03\nG00 Z10.\n"

#: Index row → [(program, error code, Syntec alarm or None, line of the error)].
CASES: dict[str, list[tuple[str, str, int | None, int]]] = {
    "A2": [("G05 P10000\nG01 X1. F100\nM08\n", "hshp-m-code", None, 3)],
    "A3": [("G05 P10000\nG43 H1 Z0\nG05 P0\n", "hshp-compensation", None, 3)],
    "A4": [("G05 P10000\nG01 X1. F100\n", "hshp-no-end", None, 1)],  # at the G05 block
    "A6": [("G61\nG05.1 Q1 E0.01\n", "smoothing-in-exact-stop", None, 2),
           ("G63\nG05.1 Q1 E0.01\n", "smoothing-in-exact-stop", None, 2)],
    "A7": [("G06.2 P3 K0 X0 Y0 Z0 F100\n", "nurbs-outside-hpcc", None, 1)],
    "A8": [("G29 X10.\n", "bad-reference", None, 1)],
    "A9": [("S0 M03\nG33 Z-5. F1.\n", "thread-speed", None, 2)],
    "A10": [("H1\nG37 R2.\n", "g37-no-z", 330, 2)],
    "A11": [("H1\nG00 Z-9.\nG37 Z-10. R2. D1.\n", "g37-start-point", 333, 3)],
    "A12": [("G37 Z-10. R2. D1.\n", "g37-no-h", 334, 1)],
    "A13": [("H1\nG37 Z-12. R1. D1.\n", "g37-early-signal", 335, 2)],
    "A14": [("H1\nG37 Z-8. R1. D1.\n", "g37-no-signal", 336, 2)],
    "A15": [("H1\nG37.1 R2.\n", "g37-no-z", 330, 2)],
    "A16": [("H1\nG00 Z-9.\nG37.1 Z-10. R2.\n", "g37-start-point", 333, 3)],
    "A17": [("G37.1 Z-10. R2.\n", "g37-no-h", 334, 1)],
    "A18": [("H1\nG37.1 Z-8. R1.\n", "g37-no-signal", 336, 2)],
    "A19": [("G41 D1 G01 X0 Y10. F100\nX20.\nG03 X24. Y14. R4.\nG01 Y30.\nG40 X0 Y0\n", "comp-interference",
             None, 3)],
    "A21": [("G41 G02 X10. R5. D1 F100\n", "comp-arc-startup", None, 1),
            ("G01 X1. F100\nG40 G03 X2. R5.\n", "comp-arc-startup", None, 2)],
    "A22": [("G41 D1 G01 X0 Y10. F100\nX20.\nY8.\nX24.\nY10.\nX40.\nG40 X40. Y0\n", "comp-interference",
             None, 4)],
    "A24": [(CYCLE + "G01 G81 X5. Z-10. R-5.\n", "cycle-group01", None, 3)],
    "A25": [(CYCLE + "G81 X5. Z-10. R-5.\nG18\n", "cycle-not-allowed", None, 4)],
    "A26": [(CYCLE + "G81 X5. Z-10. R-5. K10000\n", "bad-cycle", None, 3)],
    "A27": [(CYCLE + "G81 Z-10. R-5. K0\nG134 X0 Y0 I10. J0 K0\n", "cycle-argument", None, 4),
            (CYCLE + "G81 Z-10. R-5. K0\nG134 X0 Y0 I-10. J0 K4\n", "cycle-argument", None, 4)],
    "A28": [(CYCLE + "G83 X5. Z-10. R-5.\n", "cycle-missing-q", None, 3)],
}


@pytest.mark.parametrize(("row", "index"),
                         [(row, k) for row, cases in CASES.items() for k in range(len(cases))])
def test_manual_alarm(row: str, index: int) -> None:
    text, code, alarm, line = CASES[row][index]
    options = {"tool_measurement": PROBE, "tool_offsets": {"D": {1: 5.0}}}
    with pytest.raises(ProgramError) as info:
        interpret(text, dialect="syntec", file="case.nc", **options)
    err = info.value
    assert (err.code, err.alarm) == (code, alarm), (row, str(err))
    assert err.file == "case.nc" and err.line == line, (row, str(err))
