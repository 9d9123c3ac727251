"""Each program alarm class of the GSK 25i manual, triggered by a minimal program (docs/gsk25i_alarms.md).

The rows of docs/gsk25i_alarms.md are the error conditions the manual states in its text (E1-E11, M1-M23,
D1-D7, C1-C10, T1-T12, S1-S15) and the program-related alarms of the GSK 25i alarm list that those lack
(L1-L25). ``CASES`` holds, per row, minimal programs that must end in exactly that error: our error code, the
GSK alarm number the dialect gives it (None where the alarm list has no number for it or we have not mapped
one), the file and the 1-based line the error names. The expected values are read off the manual (condition,
alarm list) and docs/gcode.md's "Error codes" table, never from running the interpreter.

Conditions the manual says are alarms and the interpreter does not check are the ``xfail(strict=True)`` tests
at the end ("missing check" in the index): when the check is built they XPASS, strict xfail turns that into a
failure, and the marker and the index row are updated together.

tests/gcode/dialects/gsk25i/test_alarms_index.py checks that every key of ``CASES`` is a row of the index
that cites
``test_manual_alarm`` (and the other way round), and that the row's codes and alarms are those of its cases.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from gcode_helpers import program_error

from cnc_gym.gcode.dialects.gsk25i import DIALECT
from cnc_gym.machine import machine_from_dict

FILE = "alarm.nc"
NO_ALARM = None  # the alarm list has no number for the condition, or we map none (see the index)

# row -> [(program, our error code, GSK alarm number or None, line of the error)]
CASES: dict[str, list[tuple[str, str, int | None, int]]] = {
    # ------------------------------------------------------------------ E: lexical / structural
    # 33 X words after G00 make 34 words; the block limit is 32 (alarm 12 "BEYOND MAX. UNIT NO. 32").
    "E1": [("G00 X1\nG00 " + "X1 " * 33 + "\n", "too-many-words", 12, 2),
           ("G00 X1\nG00 X0000000000000001.0\n", "word-too-long", 13, 2)],
    # X takes ±999999.9999 (Table 1-1): 7 integer digits is beyond it.
    # An expression constant has at most 8 digits ("max ±99999999", §3.7.4): TOO MANY DIGITS (3).
    "E2": [("G00 X1234567\n", "value-out-of-range", 8, 1), ("#1=123456789\n", "too-many-digits", 3, 1)],
    "E3": [
        ("G01 X F100\n", "missing-value", 5, 1),  # address without data (alarm 5)
        ("G01 X1 F100 &\n", "bad-character", 9, 1),  # illegal character (9)
        ("#1=²\n", "bad-character", 9, 1),  # only ASCII digits are digits (9)
        ("G01 X1 F-100\n", "bad-sign", 6, 1),  # "-" where the address has no sign (6)
        ("G01 X1-2 F100\n", "bad-sign", 6, 1),  # "-" inside a number (6)
        ("G01 X1.2.3 F100\n", "bad-number", 7, 1),  # two decimal points (7)
        ("G01 X1.23456.7 F100\n", "bad-number", 7, 1),  # also where the increment would truncate (7)
        ("M3.5\n", "decimal-point-not-allowed", 7, 1),  # "." where the address has none (7)
    ],
    "E4": [
        ("G04 P1.5\n", "decimal-point-not-allowed", 7, 1),  # G04 P is in ms, no point (§3.2.6)
        ("G10 L50\nN1880 P1 R1.5\nG11\n", "decimal-point-not-allowed", 7, 2),  # G10 L50 R (§3.2.9)
    ],
    "E5": [
        ("G00 X1000000\n", "value-out-of-range", 8, 1),  # beyond ±999999.9999 (Table 1-1, §2.3.4)
        ("G01 X1 F1000001\n", "value-out-of-range", 8, 1),  # F 0.1~1000000 mm/min
    ],
    "E6": [("N1234567 G00 X1\n", "value-out-of-range", 16, 1)],  # N beyond 999999 (alarm 16)
    # Deviation: the manual's default is "the later one wins" (§1.3.2); we raise (the AD2 = 1 behaviour).
    "E7": [("G00 X1 X2\n", "duplicate-word", NO_ALARM, 1)],
    "E8": [
        ("G00 X1\nG12 X1\n", "unknown-code", 10, 2),  # G12 is not in the G-code table (§3.1)
        ("G22\n", "not-implemented", 10, 1),  # a GSK code without a function here (stored stroke check 2)
    ],
    "E9": [
        ("N#3 Y200.0\n", "variable-not-allowed", 205, 1),  # §3.7.2
        ("O#1\n", "variable-not-allowed", 205, 1),  # §3.7.2
        ("/#2 G00 X1\n", "variable-not-allowed", 205, 1),  # §3.7.2
    ],
    "E11": [("G00 X1 U5\n", "unsupported-axis", 15, 1)],  # the XYZ machine has no U axis
    # ------------------------------------------------------------------ M: motion
    "M1": [
        ("G00 X1\nG01 X2\n", "missing-feed", 11, 2),  # no F ever: "regarded as zero" (§3.2.2)
        ("G02 X10 I5\n", "missing-feed", 11, 1),
    ],
    "M2": [("G02 X10 I5 F0\n", "zero-feed", 25, 1)],
    # Start (0,0), centre (6,0): start radius 6, end (10,0) radius 4; 2 mm > P1810 = 0.01 mm (§3.2.3).
    "M3": [("G02 X10 I6 F100\n", "arc-radius-mismatch", 20, 1)],
    "M4": [
        ("G02 X10 R4 F100\n", "arc-impossible", 22, 1),  # chord 10 > 2R = 8
        ("G02 X10 F100\n", "arc-missing-center", 22, 1),  # neither R nor I/J
    ],
    "M5": [("G17 G02 X10 K5 F100\n", "arc-bad-offset", 21, 1)],  # K is the normal axis of G17
    "M6": [("G04 P-1\n", "bad-dwell", 18, 1), ("G04 X-1\n", "bad-dwell", 18, 1)],  # §3.2.6
    "M7": [("G10 L12 P1 R1\nG41 D1 G01 X10 F100\nG31 X20\n", "g31-in-cutter-compensation", 36, 3)],  # §3.2.8
    "M8": [("G01 X10 ,R2 F100\nG00 Y10\n", "bad-corner", NO_ALARM, 2)],  # next move G01-G03 only (§3.2.11)
    "M9": [("G01 X1 ,L5 F100\nY10\n", "bad-corner", NO_ALARM, 2)],  # chamfer 5 on a 1 mm block (§3.2.11)
    "M10": [
        ("G01 X10 ,R2 F100\nG92 X0\nY10\n", "bad-corner", NO_ALARM, 2),  # G92 in between (§3.2.11)
        ("G01 X10 ,R2 F100\nG68 X0 Y0 R10\nY10\n", "bad-corner", NO_ALARM, 3),  # G68 in between (§3.2.11)
        ("G16\nG01 X10 Y0 ,R2 F100\nX10 Y90\n", "bad-corner", NO_ALARM, 2),  # polar mode (§3.2.16)
    ],
    "M11": [
        # The first control point (11, 0) is not the current position (10, 0) (§3.2.5).
        ("G05 P10000\nG00 X10 Y0 Z0\nG06.2 P3 K0 X11 Y0 F600\nK0 X10 Y10 R0.7\nK0 X0 Y10\nK1\nK1\nK1\n",
         "nurbs-start-point", NO_ALARM, 3),
        # Rank P5 is outside 2-4 (§3.2.5).
        ("G05 P10000\nG00 X10 Y0 Z0\nG06.2 P5 K0 X10 Y0 F600\nK0 X10 Y10 R0.7\nK0 X0 Y10\nK1\nK1\nK1\n",
         "nurbs-bad-rank", NO_ALARM, 3),
    ],
    "M14": [
        ("G27 X10\n", "reference-check-failed", 46, 1),  # X10 is not the reference position (§3.3.1)
        ("G30 P5 X0\n", "bad-reference", 46, 1),  # reference positions 2-4 only
        ("G29 X0\n", "bad-reference", 46, 1),  # no intermediate point stored by G28/G30
    ],
    "M16": [("G68 X0 Y0 R30\nG18\n", "plane-change-in-rotation", NO_ALARM, 2)],  # §3.2.18
    "M17": [
        ("G68 X0 Y0 R30\nG92 X0\n", "forbidden-in-rotation", NO_ALARM, 2),  # §3.2.18
        ("G68 X0 Y0 R30\nG28 X0\n", "forbidden-in-rotation", NO_ALARM, 2),
    ],
    "M18": [
        ("G51 X0 Y0 P2\nG55\n", "forbidden-in-scaling", 109, 2),  # §3.2.17
        ("G51 X0 Y0 P2\nG28 X0\n", "forbidden-in-scaling", 109, 2),
    ],
    "M19": [("G51 X0 Y0 P0\n", "bad-scale-factor", 110, 1)],
    # §3.2.20
    "M20": [("G54.1 P49\n", "bad-offset-number", 30, 1), ("G54.1 P0\n", "bad-offset-number", 30, 1)],
    # ------------------------------------------------------------------ D: data input
    "D1": [("G10 L50 X1\nG11\n", "bad-g10", 31, 1)],  # G10 alone in its block (§3.2.9)
    "D2": [("G10 L50\nN1860 R361000\nG11\n", "bad-parameter", NO_ALARM, 2)],  # angle 361.000° (§3.2.9)
    "D3": [("G81 X0 Y0 Z-5 R1 F10\nG10 L2 P1 X0\n", "cycle-not-allowed", 61, 2)],  # §3.2.9
    "D4": [("G10 L2 P7 X10\n", "bad-g10", 31, 1), ("G10 L20 P49 X1\n", "bad-g10", 31, 1)],
    "D5": [
        ("G10 L10 P1 R1000\n", "bad-offset-value", 32, 1),  # geometry beyond ±999.999 mm (§3.5.5)
        ("G10 L11 P1 R100\n", "bad-offset-value", 32, 1),  # wear beyond ±99.999 mm
        ("#10001=100\n", "bad-offset-value", 29, 1),  # through the offset variables: 29 (not "… IN G10")
    ],
    "D6": [
        ("G01 X1 D257 F100\n", "value-out-of-range", 30, 1),  # D00-D256
        ("G43 H300 Z10\n", "value-out-of-range", 30, 1),  # H00-H256
        ("G10 L10 P0 R5\n", "bad-offset-number", 30, 1),  # H00 is always 0
    ],
    # ------------------------------------------------------------------ C: canned cycles
    "C1": [("G81 G01 X1 Z-10 R2 F100\n", "cycle-group01", 61, 1)],  # §3.4.1
    "C2": [
        ("G83 Z-10 R2 F100\n", "cycle-missing-q", 45, 1),
        ("G73 Z-10 R2 F100\n", "cycle-missing-q", 45, 1),
    ],
    "C3": [("G87 Z-10 R2 Q1 F100\n", "cycle-levels", 61, 1)],  # back boring: Z must be above R (§3.4.11)
    "C4": [
        ("M3 S500\nM29 S1000\nG00 X10\nG84 Z-10 R-2 F100\n", "rigid-tap", 61, 3),  # the move itself (§3.4.14)
        ("M3 S500\nM29 S1000\nM29\n", "rigid-tap", 61, 3),  # M29 while in M29 (§3.4.15)
        ("M3 S500\nM29 S1200\nG84 Z-10 R-2 F100\n", "rigid-tap", 200, 3),  # S above P2141/2142 = 1000
    ],
    "C5": [
        ("G81 Z-10 R2 F100\nG28 X0\n", "cycle-not-allowed", 44, 2),
        ("G81 Z-10 R2 F100\nG27 X0\n", "cycle-not-allowed", 44, 2),
    ],
    "C6": [
        ("G120 X0 Y0 I10 J0 K0\n", "cycle-argument", 225, 1),  # K = 0 (§3.6.1, "P221" in the text)
        ("G121 X0 Y0 I10 J0\n", "cycle-argument", 225, 1),  # K missing (§3.6.2)
    ],
    "C7": [
        ("G124 X0 Y0 R5 Z-5 I4 J2 P1 K1 F10\n", "cycle-argument", 61, 1),  # no drilling G code (§3.6.6)
        ("G124 G81 X0 Y0 R5 Z-5 I4 P1 K1 F10\n", "cycle-argument", 216, 1),  # J missing (§3.6.6)
        ("G125 X0 Y0 R5 Z-5 I4 J2 P1 K1 F10\n", "cycle-argument", 61, 1),
        ("G125 G81 X0 Y0 R5 Z-5 I4 P1 K1 F10\n", "cycle-argument", 216, 1),
    ],
    # U omitted with a 5 mm tool radius (D1 = 5): U < tool radius (§3.4.21).
    "C8": [
        ("G10 L12 P1 R5\nG132 X0 Y0 Z-5 R2 I50 J40 D1 L8 Q5 F100\n", "cycle-argument", 211, 2),
        ("G10 L12 P1 R5\nG133 X0 Y0 Z-5 R2 I50 J40 D1 L8 Q5 F100\n", "cycle-argument", 211, 2),
    ],
    "C9": [("G110 X0 Y0 Z-5 R2 Q2 L8 W2 V1 D1 F100\n", "cycle-argument", 215, 1)],  # I missing (§3.4.16)
    # ------------------------------------------------------------------ T: compensation
    "T1": [("G10 L12 P1 R1\nG41 D1 G02 X10 Y0 R5 F100\n", "comp-arc-startup", 34, 2)],  # §3.5.3
    "T2": [("G10 L12 P1 R3\nG00 X5 Y-5\nG01 G41 D1 X5 Y0 F100\nG03 X0 Y5 R5\nG03 X1 Y-2 I4 J-3\n"
            "G40 G01 X10 Y-2\n", "comp-no-intersection", 33, 4)],  # §3.5.3
    "T3": [("G10 L12 P1 R1\nG01 G41 D1 X10 F100\nG18\n", "comp-plane-change", 37, 3)],  # §3.5.3
    # An R5 arc under a 5 mm offset: the tool-centre arc has radius 0 (§3.5.3).
    "T4": [("G10 L12 P1 R5\nG01 G41 D1 X10 F100\nG03 X20 Y0 R5\nG01 X30\n", "comp-arc-centre", 38, 3)],
    # A 4 mm wide groove with a 3 mm radius (6 mm tool): check (a) of §3.5.3.
    "T6": [("G10 L12 P1 R3\nG01 G41 D1 X10 F100\nY-10\nX14\nY0\nX30\nG40 X40\n", "comp-interference", 41, 4)],
    "T8": [("G43 H1\n", "length-no-axis", 27, 1)],
    "T9": [
        ("H01\nG37 Z200 H01\n", "g37-h-in-block", 80, 2),  # §3.5.6
        ("G37 Z200\n", "g37-no-h", 80, 1),
    ],
    "T10": [("G41 D1\nG45 G01 X10 F100\n", "position-offset-in-comp", NO_ALARM, 2)],  # §3.5.7
    "T11": [("G02 G43 H1 X10 Y0 Z5 R5 F100\n", "length-helical", NO_ALARM, 1)],  # §3.2.3
    # ------------------------------------------------------------------ S: macros and subprograms
    "S1": [("M98 P4321\n", "program-not-found", 59, 1), ("G65 P4321\n", "program-not-found", 59, 1),
           ("M98\n", "missing-program-number", 76, 1)],
    # Main -> O1 -> O2 -> O3 -> O4 are four levels; O4's M98 P5 (line 11) is the fifth (§1.3).
    "S2": [("M98 P1\nM30\nO1\nM98 P2\nM99\nO2\nM98 P3\nM99\nO3\nM98 P4\nM99\nO4\nM98 P5\nM99\nO5\nM99\n",
            "nesting", 77, 13)],
    "S3": [("GOTO77\n", "sequence-not-found", 60, 1)],
    "S4": [
        ("WHILE[1LT2]DO1\nEND2\n", "do-end", 96, 2),  # END2 without DO2 (§3.7.5)
        ("GOTO5\nWHILE[1LT2]DO1\nN5 G00 X1\nEND1\n", "do-end", 96, 1),  # jump into a DO range (§3.7.5)
    ],
    "S5": [("#1=[[[[[[1]]]]]]\n", "bracket-nesting", 209, 1)],  # six levels; at most five (§3.7.4)
    "S6": [("#1=1/0\n", "division-by-zero", 208, 1), ("#1=5 MOD 0\n", "division-by-zero", 208, 1)],
    "S7": [("#1=SQRT[-1]\n", "math-domain", NO_ALARM, 1)],  # §3.7.5
    # Deviation (docs/gcode.md "Macros and subprograms"): the bound is ±1e47 (§3.7.7), not §3.7.2's ±999999.
    "S8": [("#1=10000000*10000000*10000000*10000000*10000000*10000000*10000000\n", "overflow", 102, 1)],
    "S9": [
        ("#0=1\n", "bad-variable", 107, 1),  # §3.7.2
        ("#5001=1\n", "read-only-variable", 107, 1),  # §3.7.3
        ("#9999=1\n", "bad-variable", 107, 1),  # no such variable
    ],
    "S10": [("G00 X1\n#3000=1 (BOOM)\n", "user-alarm", 3001, 2)],  # 3000 + n (§3.7.3)
    "S14": [
        ("G65 P0\n", "bad-call", 17, 1),  # macro program number 0
        ("M98 P10001002\nO1002\nM99\n", "bad-call", 17, 1),  # 1000 repeats, at most 999 (§1.3)
    ],
    # ------------------------------------------------------------------ L: alarm-list classes the conditions
    # lack
    "L2": [("123\n", "missing-address", 4, 1)],  # 4 ADDRESS NOT FOUND: a number without an address
    "L5": [("IF[#1]GOTO5\n", "bad-expression", 206, 1)],  # 49 CAN NOT JUDGE: a condition with no comparison
    "L8": [("G68 X0 Y0 R361\n", "bad-rotation-angle", NO_ALARM, 1)],  # 57 ANGLE PARAMETER ERROR (probable)
    "L10": [("O1\nM99\nO1\nM99\n", "duplicate-program", 73, 3)],  # 73 PROGRAM NUMBER ALREADY IN USE
    "L11": [("O10000\n", "value-out-of-range", 74, 1)],  # 74 ILLEGAL PROGRAM NUMBER: O is 4 digits (§1.2.1)
    "L15": [("WHILE[1LT2]DO4\nEND4\n", "do-end", 97, 1)],  # 97 ILLEGAL CYCLE NUMBER: DO 1-3 (§3.7.5)
    "L18": [("S99999\n", "value-out-of-range", 200, 1)],  # 200 ILLEGAL S CODE: S 0~50000
    "L19": [("M77\n", "unknown-code", 201, 1), ("M03 M08 M09 M05\n", "too-many-m-codes", 201, 1)],
    "L20": [("T1000\n", "value-out-of-range", 202, 1)],  # 202 ILLEGAL T CODE: T 0~999
    "L22": [("IF[#1EQ1]\n", "bad-macro-command", 205, 1), ("G00 X1 GOTO5\n", "bad-macro-command", 205, 1)],
    "L23": [("G00 X[1+2\n", "bad-expression", 206, 1)],
    "L24": [("G00 X[1+]\n", "missing-operand", 207, 1)],
    # 222 TOO MUCH OF TOOL RADIUS: a 60 mm tool in a 20 x 10 pocket.
    "L25": [("G10 L12 P1 R30\nG132 X0 Y0 Z-5 R2 I20 J10 U5 L8 Q2 D1 F100\n", "cycle-argument", 222, 2)],
}


PARAMS = [
    pytest.param(row, *case, id=f"{row}-{n}")
    for row, cases in CASES.items() for n, case in enumerate(cases, 1)
]


@pytest.mark.parametrize(("row", "program", "code", "alarm", "line"), PARAMS)
def test_manual_alarm(row, program, code, alarm, line):
    """One condition of the index: the program ends in one ProgramError naming the code, the controller
    alarm, the file and the line; its one-line text carries the alarm where there is one."""
    err = program_error(program, file=FILE)
    assert (err.code, err.alarm, err.file, err.line) == (code, alarm, FILE, line), (row, str(err))
    shown = f" (controller alarm {alarm})" if alarm is not None else ""
    assert str(err) == f"{FILE}:{line}: {err.message}{shown} [{code}]"


def test_m21_stroke_limit_names_the_block_that_leaves_the_travel():
    """M21 (GSK 25i operation manual §2.5.4): a move beyond the stored stroke limit is an alarm. Here: a
    machine with X/Y/Z travel -100..100 mm; line 2 ends at X150, line 3 never runs. The travel is stored
    stroke limit 1: alarm 500 "OVER TRAVEL:+n" beyond the + side, 501 "OVER TRAVEL:-n" beyond the − side (n =
    axis number)."""
    machine = machine_from_dict({"name": "tiny", "axis_defaults": {"min_position_mm": -100,
                                                                   "max_position_mm": 100}})  # fmt: skip
    err = program_error("G00 X50\nG00 X150\nG00 X0\n", file=FILE, machine=machine)
    assert (err.code, err.alarm, err.file, err.line) == ("travel-limit", 500, FILE, 2)
    assert err.message.startswith("OVER TRAVEL:+1") and "X150.0000" in err.message
    err = program_error("G00 Y-50\nG00 Y-150\n", file=FILE, machine=machine)
    assert (err.alarm, err.line) == (501, 2) and err.message.startswith("OVER TRAVEL:-2")
    # An arc whose ends are inside but whose far side is not: centre (60, 0), radius 50 reaches X 110.
    err = program_error("G00 X10\nG01 Z0 F100\nG02 I50\n", file=FILE, machine=machine)
    assert (err.code, err.line) == ("travel-limit", 3)


def test_c10_drilling_axis_change_in_a_cycle_with_fxy():
    """C10 (§3.4.3): "before the drilling axis can be changed, the canned cycle must be cancelled". With the
    standard 2000#0 FXY = 0 the drilling axis is always Z, so it cannot change; with FXY = 1 the plane picks
    it, and a plane change inside the cycle is alarm 61."""
    fxy = replace(DIALECT, cycle_params=replace(DIALECT.cycle_params, drilling_axis_follows_plane=True))
    err = program_error("G90 G99 G81 X10 Y5 Z-20 R-2 F100\nG18 X20\n", file=FILE, dialect=fxy)
    assert (err.code, err.alarm, err.file, err.line) == ("cycle-not-allowed", 61, FILE, 2)


# ---------------------------------------------------------------------- missing checks (the LEAD builds them)
def test_e1_word_longer_than_16_characters_is_alarm_13():
    """E1 / alarm 13 "A UNIT CHARACTER STRING EXCEEDS 16": `X0000000000000001.0` is 19 characters (its value
    1 mm is in range, so only the length can refuse it). The code name `word-too-long` is a proposal.
    Words holding an expression (`X[#101*COS[#102]]`) are not meant: the manual's own macro examples
    exceed 16 characters there."""
    err = program_error("G00 X1\nG00 X0000000000000001.0\n", file=FILE)
    assert (err.code, err.alarm, err.file, err.line) == ("word-too-long", 13, FILE, 2)
