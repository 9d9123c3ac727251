"""The ``fanuc`` dialect (generic Fanuc 0i-M / Haas-class mill): each difference from the GSK 25i
(docs/fanuc.md), and shop programs written in the style of common CAM post-processors and of hand-written
Haas programs.

Expected points are worked out by hand in the comments: machine = program + G54 (zero here) + the tool
length vector (H, type A: on Z).
"""

from __future__ import annotations

import pytest
from gcode_helpers import close, moves, program_error, records

from cnc_gym.errors import ConfigError
from cnc_gym.gcode import get_dialect, interpret
from cnc_gym.machine import machine_from_dict

FANUC = "fanuc"


def ends(text: str, **kw) -> list[list[float]]:
    return [m["end"] for m in moves(text, dialect=FANUC, **kw)]


# --------------------------------------------------------------------------- numbers and programs
def test_numbers_without_a_decimal_point_are_least_increments():
    # Parameter 3401#0 DPI = 0 (the Fanuc standard), IS-B: X1000 = 1 mm; X1. = 1 mm; the GSK 25i reads X1000
    # as 1000 mm (its DPI = 1).
    assert ends("G00 X1000 Y2.5\n") == [[1.0, 2.5, 0.0]]
    assert [m["end"] for m in moves("G00 X1000\n")] == [[1000.0, 0.0, 0.0]]
    # G04 X1500 = 1.5 s (X in 0.001 s), P in ms.
    dwells = [r["seconds"] for r in records("G04 X1500\nG04 P250\nG04 X2.\n", dialect=FANUC)]
    assert dwells == [1.5, 0.25, 2.0]


def test_colon_is_the_program_number_address_and_o_numbers_have_8_digits():
    text = ":1234 (MAIN)\nG00 X1.\nM98 P12345678\nM30\nO12345678 (SUB)\nG00 Y2.\nM99\n"
    assert ends(text) == [[1.0, 0.0, 0.0], [1.0, 2.0, 0.0]]
    # With 8-digit program numbers P is the number itself; the repeat count is L (P21002 is O21002).
    sub = "O1\nM98 P21002\nM30\nO21002\nG91 G00 X1.\nM99\n"
    assert ends(sub) == [[1.0, 0.0, 0.0]]
    assert ends("O1\nM98 P21002 L3\nM30\nO21002\nG91 G00 X1.\nM99\n")[-1] == [3.0, 0.0, 0.0]
    # The GSK 25i: 4-digit O numbers, P21002 = O1002 twice; a 5-digit O is out of range (alarm 74).
    assert program_error(":1234\n").code == "bad-character"
    assert program_error("O12345678\n").code == "value-out-of-range"


# --------------------------------------------------------------------------- G43 H without an axis word
def test_g43_h_alone_puts_the_offset_in_force_for_the_next_z_move():
    offsets = {"H": {1: 100.0}}
    # G90: Z10. after G43 H1 → machine Z 110; the XY move between does not move Z.
    out = ends("G00 X5.\nG43 H1\nG00 X6.\nZ10.\nZ20.\n", tool_offsets=offsets)
    assert out == [[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [6.0, 0.0, 110.0], [6.0, 0.0, 120.0]]
    # G91: the next Z move carries the vector too: 0 + 100 - 5 = 95.
    assert ends("G91 G43 H1\nG00 Z-5.\n", tool_offsets=offsets) == [[0.0, 0.0, 95.0]]
    # G49 alone cancels it for the next absolute move.
    assert ends("G43 H1\nG00 Z10.\nG49\nG00 Z10.\n", tool_offsets=offsets)[-1] == [0.0, 0.0, 10.0]
    # The GSK 25i needs an axis word in the block (alarm 27).
    err = program_error("G43 H1\nG00 Z10.\n", tool_offsets=offsets)
    assert err.code == "length-no-axis" and err.alarm == 27


# --------------------------------------------------------------------------- safe-start lines
def test_g00_beside_g28_only_sets_the_modal_motion():
    # "G00 G28 G91 Z0": G28 via the incremental intermediate point Z+0 to reference Z0; G00 is then the
    # modal motion (the next axis-only block is a rapid).
    out = moves("G01 Z50. F100.\nG00 G28 G91 Z0.\nG90 X10.\n", dialect=FANUC)
    assert [(m["kind"], m["end"]) for m in out] == [("line", [0.0, 0.0, 50.0]), ("rapid", [0.0, 0.0, 0.0]),
                                                   ("rapid", [10.0, 0.0, 0.0])]  # fmt: skip
    assert program_error("G00 G28 G91 Z0.\n").code == "axis-word-conflict"  # the GSK 25i
    # Two codes that take the axis words stay an error.
    assert program_error("G28 G51.1 Z0.\n", dialect=FANUC).code == "axis-word-conflict"


# --------------------------------------------------------------------------- AND / OR
@pytest.mark.parametrize(("condition", "taken"), [
    ("#1 GT 0 AND #2 LT 5", True), ("#1 GT 0 AND #2 GT 5", False), ("#1 LT 0 OR #2 EQ 2", True),
    ("[#1 GT 0] AND [#2 LT 5]", True), ("[#1 LT 0] OR [#2 GT 5]", False),
    ("#1 LT 0 AND #2 EQ 2 OR #1 EQ 1", True),  # AND before OR: (F and T) or T
    ("[#1 AND 3] EQ 1", True),  # inside an operand's brackets AND is the bitwise operator (1 AND 3 = 1)
])  # fmt: skip
def test_conditions_combine_with_and_or(condition, taken):
    text = f"#1=1\n#2=2\nIF[{condition}]GOTO10\nG00 X1.\nN10 G00 Y1.\n"
    assert (ends(text)[0] == [0.0, 1.0, 0.0]) is taken


def test_while_with_and_counts_to_the_first_failing_comparison():
    text = "#1=0\nWHILE[#1 LT 10 AND #1 LT 3]DO1\n#1=#1+1\nG00 X#1\nEND1\n"
    assert [e[0] for e in ends(text)] == [1.0, 2.0, 3.0]  # a variable's value is in mm whatever DPI
    assert program_error("#1=0\nIF[#1 LT 10 AND #1 LT 3]GOTO5\n").code == "bad-expression"  # the GSK 25i


# --------------------------------------------------------------------------- G95, M19
def test_g95_feed_per_revolution_follows_the_spindle_speed():
    out = moves("S1000 M03\nG95 G01 X10. F0.2\nS500\nX20.\nG94 F300.\nX30.\n", dialect=FANUC)
    assert [m["feed"] for m in out] == [200.0, 100.0, 300.0]  # 0.2 mm/rev × 1000 r/min, then × 500
    assert [m["end"][0] for m in out] == [10.0, 20.0, 30.0]
    err = program_error("S1000 M03\nG01 X1. F100.\nG95\nX2.\n", dialect=FANUC)  # the unit changed: F again
    assert err.code == "missing-feed" and "G95" in err.message
    err = program_error("G95 G01 X1. F0.2\n", dialect=FANUC)  # no spindle speed
    assert "spindle speed" in err.message
    assert program_error("G95\n").code == "not-implemented"  # the GSK 25i


def test_m19_oriented_spindle_stop_is_recorded():
    tp = interpret("S800 M03\nG00 X1.\nM19\nG00 X2.\n", dialect=FANUC)
    rows = tp.to_records()
    assert rows[1] == {"kind": "dwell", "line": 3, "seconds": 0.0, "modes": ["exact_stop"]}
    assert float(tp.spindle_rpm[0]) == 800.0 and float(tp.spindle_rpm[2]) == 0.0
    assert program_error("M19\n").code == "not-implemented"  # the GSK 25i


def test_machine_m_codes_are_machine_functions_listed_on_the_tool_path():
    """An M code the control does not define is handed to the machine: no motion of the program, the block
    ends at rest when the machine answers (a 0 s exact-stop dwell flagged machine_function, its code in the
    trace record). One of the usual machine codes (M13, M88 …) passes silently, another (M20) with a note;
    a preset's machine_functions lists its own codes and its strict setting refuses the rest."""
    tp = interpret("S1000 M13\nG01 X1. F100.\nM88\nM20\nM30\n", dialect=FANUC)
    dwells = [r for r in tp.to_records() if r["kind"] == "dwell"]
    assert [(r["line"], r["machine_function"]) for r in dwells] == [(1, "M13"), (3, "M88"), (4, "M20")]
    assert all(r["seconds"] == 0.0 and r["modes"] == ["exact_stop", "machine_function"] for r in dwells)
    assert dict(tp.machine_functions) == {0: "M13", 2: "M88", 3: "M20"}
    assert len(tp.notices) == 1 and tp.notices[0].startswith("<program>:4: note: M20 is not on this machine")
    # In cutter compensation the machine function waits in the look-ahead: the contour is unchanged.
    text = "G41 D1 G01 X10. Y0 F100.\n{m}X20.\nG40 X30. Y-10.\n"
    plain = [r["end"] for r in records(text.format(m=""), dialect=FANUC, tool_offsets={"D": {1: 2.0}})]
    with_m = records(text.format(m="M88\n"), dialect=FANUC, tool_offsets={"D": {1: 2.0}})
    assert [r["end"] for r in with_m if r["kind"] != "dwell"] == plain
    # The preset's list (any dialect) and its strict setting.
    shop = machine_from_dict({"machine_functions": {"m_codes": {20: "part counter"}, "strict": True}})
    listed = interpret("M20\nM88\n", dialect=FANUC, machine=shop).machine_functions
    assert dict(listed) == {0: "M20", 1: "M88"}
    assert program_error("M123\n", dialect=FANUC, machine=shop).message.endswith("(machine_functions.strict)")
    assert dict(interpret("M20\n", machine=shop).machine_functions) == {0: "M20"}  # the GSK 25i too
    # The GSK 25i refuses the others, and its M97 (a macro interrupt) by name; Haas's M97 is a call
    # (below), never a machine function.
    assert program_error("M88\n").message == "unknown M code M88"
    err = program_error("M97 P100\n")
    assert err.code == "not-implemented" and "M97" in err.message


# --------------------------------------------------------------------------- Haas M97 local subprograms
LOCAL = """G90 G00 X0 Y0 Z5.
G01 Z-1. F200.
M97 P100 L2
G00 X50. Y0.
M97 P100{third}
G00 Z5.
M30
N100 G91 G01 X10. F500.
Y10.
X-10.
Y-10.
G90
M99
"""


def test_m97_runs_the_local_subprogram_l_times_and_returns_after_the_call():
    ends = [r["end"][:2] for r in records(LOCAL.format(third=""), dialect=FANUC) if r["kind"] == "line"]
    square = [[10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]]
    shifted = [[x + 50.0, y] for x, y in square]
    assert ends == [[0.0, 0.0], *square, *square, *shifted]
    tp = interpret(LOCAL.format(third=""), dialect=FANUC)
    assert list(tp.line[tp.kind == 0][-2:]) == [4, 6]  # the rapids after each call: the calls returned
    # L0 does not call; a local subprogram may call another one.
    zero = records(LOCAL.format(third=" L0"), dialect=FANUC)
    assert len([r for r in zero if r["kind"] == "line"]) == 9
    nested = "M97 P10\nM30\nN10 G91 G01 X1. F100.\nM97 P20\nM99\nN20 Y1.\nM99\n"
    assert [r["end"][:2] for r in records(nested, dialect=FANUC)] == [[1.0, 0.0], [1.0, 1.0]]


@pytest.mark.parametrize(("text", "code", "words"), [
    ("M97\nM30\n", "bad-call", "needs P"),
    ("M97 P200\nM30\nN100 X1.\nM99\n", "sequence-not-found", "N200"),
    ("M97 P100 L10000\nM30\nN100 X1.\nM99\n", "bad-call", "repeat count"),
    ("M97 P1\nM30\nN1 M97 P1\nM99\n", "nesting", "nest at most"),
])
def test_m97_errors_are_one_line(text, code, words):
    err = program_error(text, dialect=FANUC)
    assert err.code == code and words in err.message, err.message


# --------------------------------------------------------------------------- abbreviated macro words
ABBREVIATED = """#1=0
#2=0
WH[#1LT3]DO1
#1=#1+1
#2=#2+SQ[16]
G01 X#2 F100.
EN1
IF[#1EQ3]GO20
G00 Y99.
N20 #3=#1AN2
IF[#3EQ2]TH#4=AT[1]/[1]
G00 Y#4
"""


def test_abbreviated_macro_words_are_the_words():
    """Fanuc reads the first two letters of a macro word as the word: WH[ is WHILE[, EN1 END1, GO20 GOTO20,
    TH THEN, SQ[ SQRT[, AT[ ATAN[, AN AND. Three passes add SQRT[16] = 4 to X; GO20 skips Y99; 3 AND 2 = 2,
    so #4 = ATAN[1]/[1] = 45."""
    full = ABBREVIATED
    for short, word in (("WH[", "WHILE["), ("EN1", "END1"), ("GO20", "GOTO20"), ("TH#", "THEN#"),
                        ("SQ[", "SQRT["), ("AT[", "ATAN["), ("AN2", "AND2")):  # fmt: skip
        full = full.replace(short, word)
    assert ends(ABBREVIATED) == ends(full)
    assert ends(ABBREVIATED) == [[4.0, 0.0, 0.0], [8.0, 0.0, 0.0], [12.0, 0.0, 0.0], [12.0, 45.0, 0.0]]
    # Never where an address stands or inside a full word: WH without '[' is W and H, AND stays AND.
    assert program_error("WH2\n", dialect=FANUC).code == "missing-value"  # W without a number
    assert ends("#1=5AND4\nG00 X#1\n") == [[4.0, 0.0, 0.0]]
    # The GSK 25i has no abbreviations: WH[ is an error there.
    err = program_error("#1=0\nWH[#1LT3]DO1\nEND1\n")
    assert err.code == "missing-value" and "write WHILE[…]DOn in full" in err.message


# --------------------------------------------------------------------------- Haas cycle and dwell rules
def test_haas_cycles_without_r_drill_from_the_initial_level():
    # No R ever given: the R level is the initial level (Z10): rapid over the hole, feed from Z10 to Z-5,
    # back to Z10. The GSK 25i needs R in the first drilling block.
    text = "G00 X0 Y0 Z10.\nG81 X1. Y1. Z-5. F100.\nX2.\nG80\n"
    assert ends(text) == [[0.0, 0.0, 10.0], [1.0, 1.0, 10.0], [1.0, 1.0, -5.0], [1.0, 1.0, 10.0],
                          [2.0, 1.0, 10.0], [2.0, 1.0, -5.0], [2.0, 1.0, 10.0]]  # fmt: skip
    assert program_error(text).code == "cycle-missing-data"


def test_haas_l_is_the_cycle_repeat_count():
    # G91 with L3: three holes 5 apart; R-8 from the initial level 10 is 2, Z-5 from R is -3.
    holes = [e for e in ends("G00 Z10.\nG91 G81 X5. Z-5. R-8. F100. L3\nG90 G80\n") if e[2] == -3.0]
    assert holes == [[5.0, 0.0, -3.0], [10.0, 0.0, -3.0], [15.0, 0.0, -3.0]]
    assert ends("G00 Z10.\nG81 X1. Z-1. R2. F100. L0\n") == [[0.0, 0.0, 10.0]]  # L0 stores the data only
    assert program_error("G81 X1. Z-1. R2. F100. K2 L2\n", dialect=FANUC).code == "bad-cycle"
    assert program_error("G81 X1. Z-1. R2. F100. L2\n").code == "unused-word"  # the GSK 25i: K only


def test_haas_dwell_p_with_a_decimal_point_is_seconds():
    # Haas: "P10. is 10 seconds, P10 10 milliseconds" — G04 and a cycle's P alike; the GSK 25i refuses the
    # point.
    dwells = [r["seconds"] for r in records("G04 P1.5\nG04 P1500\nG82 X1. Z-1. R2. P0.5 F100.\n",
                                           dialect=FANUC) if r["kind"] == "dwell"]  # fmt: skip
    assert dwells == [1.5, 1.5, 0.5]
    assert program_error("G04 P1.5\n").code == "decimal-point-not-allowed"


# --------------------------------------------------------------------------- G47 text engraving (Haas)
def test_g47_engraves_the_comments_text_in_single_strokes():
    """G47 P0 (TEXT): each stroke of the font at J/6 per grid unit, from X Y along I degrees: rapid to the
    stroke's start, to R, plunge to Z at E, cut at F, back to R. "LI" at J6 (1 mm per unit), X10 Y20, I0:
    L is one stroke (0,6)-(0,0)-(4,0); I three ((1,6)-(3,6), (2,6)-(2,0), (1,0)-(3,0)) 6 units on."""
    text = "G00 Z5.\nG47 P0 (li) X10. Y20. J6. R2. Z-1. F300. E100.\n"
    rows = [(r["kind"], r["end"], r.get("feed")) for r in records(text, dialect=FANUC)][1:]
    expected = [("rapid", [10.0, 26.0, 5.0], None), ("rapid", [10.0, 26.0, 2.0], None),
                ("line", [10.0, 26.0, -1.0], 100.0), ("line", [10.0, 20.0, -1.0], 300.0),
                ("line", [14.0, 20.0, -1.0], 300.0)]  # fmt: skip
    for x0, y0, x1, y1 in ((17, 26, 19, 26), (18, 26, 18, 20), (17, 20, 19, 20)):
        expected += [("rapid", [expected[-1][1][0], expected[-1][1][1], 2.0], None),
                     ("rapid", [float(x0), float(y0), 2.0], None),
                     ("line", [float(x0), float(y0), -1.0], 100.0),
                     ("line", [float(x1), float(y1), -1.0], 300.0)]  # fmt: skip
    expected.append(("rapid", [19.0, 20.0, 2.0], None))
    assert rows == expected
    # I turns the line of text about X Y: "-" at I90 is the stroke (1,3)-(3,3) turned up: x = 10 - 3.
    dash = [r["end"] for r in records("G47 P0 (-) X10. Y0 J6. I90. R2. Z-1. F300.\n", dialect=FANUC)]
    assert [round(c, 9) + 0.0 for c in dash[-2]] == [7.0, 3.0, -1.0]


def test_g47_serial_numbers_characters_and_errors():
    # P1: #599 in as many digits as the comment has '#', then #599 + 1; P32-P126 one character.
    serial = "#599=41\nG47 P1 (####) X0 Y0 J6. R1. Z-1. F100.\nG47 P1 (####) X0 Y0 J6. R1. Z-1.\n"
    spelled = "G47 P0 (0041) X0 Y0 J6. R1. Z-1. F100.\nG47 P0 (0042) X0 Y0 J6. R1. Z-1.\n"
    assert ends(serial) == ends(spelled)
    assert ends("G47 P45 X0 Y0 J6. R1. Z-1. F100.\n") == ends("G47 P0 (-) X0 Y0 J6. R1. Z-1. F100.\n")
    assert program_error("G47 P0 X0 Y0 J6. R1. Z-1. F100.\n", dialect=FANUC).code == "engrave-no-text"
    assert program_error("G47 P0 (a~b) X0 Y0 R1. Z-1. F100.\n", dialect=FANUC).code == "bad-engrave"
    assert program_error("G47 P0 (A) X0 Y0 R1. F100.\n", dialect=FANUC).code == "missing-value"
    assert program_error("G91 G47 P0 (A) X0 Y0 R1. Z-1. F100.\n", dialect=FANUC).code == "bad-engrave"
    # The GSK 25i's G47 is the position offset double increase, never an engraving.
    assert program_error("G47 P0 (A) X0 Y0 R1. Z-1. F100.\n").code == "unused-word"


def test_the_engraving_font_stays_in_its_cell():
    from cnc_gym.gcode.dialects.fanuc.engraving import ADVANCE, CAP_HEIGHT, FONT

    for char, glyph in FONT.items():
        for stroke in glyph:
            assert len(stroke) >= 2, char
            assert all(0 <= x <= 4 < ADVANCE and -1 <= y <= CAP_HEIGHT for x, y in stroke), char


# --------------------------------------------------------------------------- Haas system variables
def test_haas_tool_life_table_and_timers_are_read_only():
    """#5400+n / #5500+n: the feed and total seconds of tool n so far (nominal: programmed feed, rapids at
    6000 mm/min); #5600+n limits 0; #3026 the tool in the spindle, #3027 the spindle speed, #3022 the feed
    timer. Tool 5 cut 60 mm at 600 mm/min: 6 s. Writing one is alarm 116."""
    text = ("T5 M06\nG01 X60. F600.\n#1=#5405\n#2=#5505\n#3=#5401\n#4=#3026\nS1200 M03\n#5=#3027\n"
            "#6=#5605\n#7=#3022\nG00 X#1 Y#2 Z#4\nX#5 Y#6 Z#7\nY#3\n")  # fmt: skip
    assert ends(text)[1:] == [[6.0, 6.0, 5.0], [1200.0, 0.0, 6.0]]
    err = program_error("#5405=1\n", dialect=FANUC)
    assert (err.code, err.alarm) == ("read-only-variable", 116) and "GSK" not in err.message
    assert program_error("#1=#5405\n").code == "bad-variable"  # not a GSK 25i variable
    # The Haas tool life check of a shop program: a fresh tool passes (#5405 = 0 < 6000).
    assert ends("T5 M06\nIF [ #5405 GE 6000 ] THEN #3000= 15 (TOOL LIFE EXPIRED)\nG00 X1.\n") == [
        [1.0, 0.0, 0.0]]


# --------------------------------------------------------------------------- the 4-axis preset
def test_vmc_4axis_is_vmc_small_with_an_a_table():
    from cnc_gym.machine import load_machine

    four, small = load_machine("vmc-4axis"), load_machine("vmc-small")
    assert four.rotary_letters == "A" and four.axes == small.axes and four.controller == small.controller
    rows = records("G00 X10. A90.\nG01 X20. A180. F1000.\n", dialect=FANUC, machine=four)
    assert [r["rotary_end"] for r in rows] == [{"A": 90.0}, {"A": 180.0}]
    err = program_error("G00 X10. A90.\n", dialect=FANUC, machine=small)
    assert err.code == "unsupported-axis" and "--machine vmc-4axis has A" in err.message


# --------------------------------------------------------------------------- calculator-type input
MIXED = "G00 Z2\nX1.292 Y3.752\nG01 X26.377 Y31 F600\nG03 X26.937 Y30.161 I4.507 J2.402\n"


def test_calculator_type_input_reads_integers_as_mm():
    """Parameter 3401#0 DPI = 1 (calculator_input): X10 is 10 mm, G04 X2 2 s, K3 3 repeats; a preset's
    calculator_input sets it, the argument rules. Dialects without the setting refuse it."""
    assert ends("G00 X10 Y2.5\n", calculator_input=True) == [[10.0, 2.5, 0.0]]
    assert ends("G00 X10 Y2.5\n") == [[0.01, 2.5, 0.0]]
    assert [r["seconds"] for r in records("G04 X2\n", dialect=FANUC, calculator_input=True)] == [2.0]
    calculator = machine_from_dict({"calculator_input": True})
    assert ends("G00 X10\n", machine=calculator) == [[10.0, 0.0, 0.0]]
    assert ends("G00 X10\n", machine=calculator, calculator_input=False) == [[0.01, 0.0, 0.0]]
    assert [m["end"] for m in moves("G00 X10\n", calculator_input=True)] == [[10.0, 0.0, 0.0]]  # GSK: as ever
    with pytest.raises(ConfigError, match="no calculator-type input setting"):
        interpret("G00 X10\n", dialect="syntec", calculator_input=True)


def test_mixed_decimal_points_get_a_warning_and_the_arc_error_names_the_block():
    # Y31 next to decimal Y words: one warning naming the first integer word. The arc after it fails its
    # radius check, and the error names Y31's block as the one that set the start point.
    tp = interpret("G00 Z2\nX1.5 Y3.\nG01 X26 F600\nX4.\n", dialect=FANUC)
    assert tp.notices == ("<program>:3: warning: X26 has no decimal point and reads 0.026 mm (26 least input "
                          "increments, parameter 3401#0 DPI = 0), while other X words have one: if the "
                          "program means X26. (26 mm), trace it with --calculator-input (the machine "
                          "preset's calculator_input) [mixed-decimal-point]",)  # fmt: skip
    assert interpret("G00 X10 Y20\nX0 Y5\n", dialect=FANUC).notices == ()  # integers alone: no warning
    err = program_error(MIXED, dialect=FANUC)
    assert err.code == "arc-radius-mismatch" and err.line == 4
    assert err.message.endswith("; Y31 at line 3 (the start point) without a decimal point: least input "
                                "increments (parameter 3401#0 DPI = 0: Y31 is 0.031 mm); if they mean mm, "
                                "trace with --calculator-input")  # fmt: skip
    assert err.notices and "[mixed-decimal-point]" in err.notices[0]  # the warning goes with the error
    assert ends(MIXED, calculator_input=True)[2] == [26.377, 31.0, 2.0]


def test_cnc_gym_trace_prints_the_warning_before_the_error_it_explains(tmp_path, capsys):
    from cnc_gym.cli import main

    path = tmp_path / "mixed.nc"
    path.write_text(MIXED)
    assert main(["trace", str(path), "--dialect", "fanuc"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2 and lines[0].endswith("[mixed-decimal-point]")
    assert lines[1].endswith("[arc-radius-mismatch]")


# --------------------------------------------------------------------------- the shop example
def test_the_haas_style_shop_example_traces_with_its_setup():
    """examples/haas_shop.nc with examples/shop_setup.yaml: coolant through the spindle as machine
    functions, an abbreviated WH loop of two contour passes in G41, a G82 spot cycle without R repeated by
    L with a P dwell in seconds, a G47 engraving; every Z carries G54 (-380) and the tool's length."""
    from pathlib import Path

    from cnc_gym.gcode import interpret_file

    root = Path(__file__).resolve().parents[4] / "examples"
    tp = interpret_file(root / "haas_shop.nc", dialect=FANUC, setup=root / "shop_setup.yaml")
    assert tp.notices == ()
    assert list(tp.machine_functions.values()) == ["M88", "M89"]  # (M08/M09 are the dialect's own)
    rows = tp.to_records()
    cut = {round(r["end"][2], 6) for r in rows if r["kind"] == "line" and r["line"] < 27}
    assert {-380.0 + 112.4 - 4.0, -380.0 + 112.4 - 6.0} <= cut  # the two passes, Z-4 and Z-6 (H1 112.4)
    spots = [r for r in rows if r["kind"] == "dwell" and r["seconds"] == 0.5]
    assert len(spots) == 4  # L4
    engraved = {round(r["end"][2], 6) for r in rows if r["kind"] == "line" and r["line"] == 38}
    assert engraved == {round(-380.0 + 104.10 - 0.02 - 0.2, 6)}


# --------------------------------------------------------------------------- G92 and G54-G59
def test_g92_shifts_every_work_system_and_stays_across_g54_g59():
    """Fanuc 0i: G92 sets a shift that applies to all of G54-G59 and stays until reset or reference
    return; the GSK 25i's G92 replaces the work system until the next G54-G59 (§3.2.13). G55 = (100, 0).
    At machine (10, 10) in G54, G92 X0 Y0 makes the shift (10, 10): G54 X5 is machine 15; G55 X5 is
    100 + 10 + 5 = 115; G54 again keeps it (15)."""
    text = "G10 L2 P2 X100.\nG00 X10. Y10.\nG92 X0 Y0\nG54 X5. Y5.\nG55 X5. Y5.\nG54 X5. Y5.\n"
    assert ends(text) == [[10.0, 10.0, 0.0], [15.0, 15.0, 0.0], [115.0, 15.0, 0.0], [15.0, 15.0, 0.0]]
    # The GSK 25i: G54 ends the G92 system, G55 is its own offset only.
    gsk = [m["end"] for m in moves(text)]
    assert gsk == [[10.0, 10.0, 0.0], [5.0, 5.0, 0.0], [105.0, 5.0, 0.0], [5.0, 5.0, 0.0]]
    # A second G92 replaces the shift (from where the tool is): at machine 15, X0 → shift 15.
    assert ends("G00 X10.\nG92 X0\nG00 X5.\nG92 X0\nG55 X1.\n")[-1] == [16.0, 0.0, 0.0]


# --------------------------------------------------------------------------- power-on units
HAAS_INCH = """%
O40002 (HAAS STYLE, INCH MACHINE, NO G20)
(T1 0.5 FLAT ENDMILL)
G00 G17 G40 G49 G80 G90
T1 M06
G00 G90 G54 X1. Y1. S3000 M03
G43 H01 Z1. M08
G01 Z-0.1 F10.
X2. F20.
G03 X2.5 Y1.5 R0.5
G00 Z1. M09
G00 G28 G91 Z0.
G28 X0. Y0.
M30
%
"""


def test_a_haas_inch_program_without_g20_on_an_inch_machine():
    # units="inch": the input unit at power-on (a controller parameter); H1 = 4 in = 101.6 mm.
    tp = interpret(HAAS_INCH, dialect=FANUC, units="inch", tool_offsets={"H": {1: 101.6}})
    rows = [r for r in tp.to_records() if r["kind"] != "dwell"]
    assert close(rows[0]["end"], [25.4, 25.4, 0.0])  # X1. Y1.
    assert close(rows[1]["end"], [25.4, 25.4, 25.4 + 101.6])  # Z1. + H1
    assert close(rows[2]["end"], [25.4, 25.4, -2.54 + 101.6]) and close(rows[2]["feed"], 254.0)
    arc = rows[4]
    assert arc["kind"] == "arc" and close(arc["end"], [63.5, 38.1, 99.06]) and close(arc["radius"], 12.7)
    assert close(arc["feed"], 508.0)  # F20. in/min
    assert close(rows[-1]["end"], [0.0, 0.0, 0.0])  # G28 X0. Y0. in G91: to the reference position
    # The same text read in mm is another part (X1. = 1 mm); a program's own G20 rules over units="mm".
    assert close(moves(HAAS_INCH, dialect=FANUC)[0]["end"], [1.0, 1.0, 0.0])
    g20 = HAAS_INCH.replace("G00 G17 G40", "G20 G00 G17 G40")
    assert close(moves(g20, dialect=FANUC, units="mm")[0]["end"], [25.4, 25.4, 0.0])


def test_units_is_checked():
    with pytest.raises(Exception, match="units must be 'mm' or 'inch'"):
        interpret("G00 X1\n", units="cm")


# --------------------------------------------------------------------------- CAM-style programs
FUSION = """%
O1001 (BRACKET)
(T1  D=10. CR=0. - ZMIN=-5. - FLAT END MILL)
(T2  D=6.8 CR=0. TAPER=118DEG - ZMIN=-12. - DRILL)
N10 G90 G94 G17
N15 G21
N20 G53 G0 Z0.

(2D CONTOUR1)
N25 T1 M6
N30 S8000 M3
N35 G54
N40 G0 X-15. Y-5.
N45 G43 Z15. H1
N50 G0 Z5.
N55 G1 Z-5. F800.
N60 G1 Y40. F1200.
N65 G2 X-5. Y50. R10.
N70 G1 X45.
N75 G2 X55. Y40. I0. J-10.
N80 G1 Y0.
N85 G0 Z15.
N90 M9
N95 G53 G0 Z0.

(DRILL1)
N100 T2 M6
N105 S2500 M3
N110 G54
N115 G0 X10. Y20.
N120 G43 Z15. H2
N125 M8
N130 G0 Z5.
N135 G98 G83 X10. Y20. Z-12. R5. Q3. F250.
N140 X30.
N145 G80
N150 M9
N155 G53 G0 Z0.
N160 M5
N165 G53 G0 X0. Y0.
N170 M30
%
"""


def test_a_fusion_style_program():
    tp = interpret(FUSION, dialect=FANUC, tool_offsets={"H": {1: 100.0, 2: 120.0}})
    rows = [r for r in tp.to_records() if r["kind"] != "dwell"]
    lines = enumerate(FUSION.splitlines(), 1)
    line = {int(text.split()[0][1:]): n for n, text in lines if text.startswith("N")}
    at = {}
    for r in rows:
        at.setdefault(r["line"], []).append(r)
    assert at[line[45]][0]["end"] == [-15.0, -5.0, 115.0]  # N45 G43 Z15. H1: Z 15 + 100
    arc = at[line[65]][0]  # N65 G2 X-5. Y50. R10.: from (-15, 40), centre (-5, 40), a CW quarter
    assert arc["center"] == [-5.0, 40.0, 95.0] and arc["sweep_deg"] == -90.0
    arc = at[line[75]][0]  # N75 G2 X55. Y40. I0. J-10.: from (45, 50), centre (45, 40)
    assert arc["center"] == [45.0, 40.0, 95.0] and arc["sweep_deg"] == -90.0
    assert at[line[95]][0]["end"] == [55.0, 0.0, 0.0]  # N95 G53 G0 Z0.: machine Z0
    # N135 G83 Q3 from R5 (Z 125 with H2): pecks to 2, -1, -4, -7, -10, -12 (+120), then back to the
    # initial level Z5 (G98); N140 the same at X30.
    feeds = [r["end"] for r in rows if r["kind"] == "line" and r["line"] in (line[135], line[140])]
    depths = [2.0, -1.0, -4.0, -7.0, -10.0, -12.0]
    assert feeds == [[x, 20.0, d + 120.0] for x in (10.0, 30.0) for d in depths]
    assert at[line[135]][-1]["end"] == [10.0, 20.0, 125.0]
    assert rows[-1]["end"] == [0.0, 0.0, 0.0]  # N165 G53 G0 X0. Y0.
    assert tp.tool[-1] == 2 and int(tp.spindle_rpm[-1]) == 0  # T2, M5


MASTERCAM = """%
O0100(PLATE)
(DATE=DD-MM-YY - 12-05-23 TIME=HH:MM - 10:20)
(MATERIAL - ALUMINUM MM - 2024)
( T3 |  8. FLAT ENDMILL | H3 | D3 )
N100 G21
N102 G0 G17 G40 G49 G80 G90
N104 T3 M6
N106 G0 G90 G54 X0. Y-10. S6000 M3
N108 G43 H3 Z25.
N110 Z5.
N112 G1 Z-2. F300.
N114 G41 D3 Y0. F600.
N116 X40.
N118 Y30.
N120 X0.
N122 Y0.
N124 G40 X-10.
N126 G0 Z25.
N128 M5
N130 G91 G28 Z0.
N132 G28 X0. Y0.
N134 M30
%
"""


def test_a_mastercam_style_program_with_cutter_compensation():
    # The 40 x 30 rectangle from (0, 0) run counter-clockwise with G41 (left = inside) and D3 = 4: the tool
    # centre runs 4 inside. Start-up type A: perpendicular to the next block at its start, (0, 0) + 4·(+Y);
    # the inner corners are the offset lines' intersections (36, 4), (36, 26), (4, 26); the turn into the
    # cancel block (-Y then -X) is an outer corner: perpendicular to the last block at its end, (4, 0); then
    # straight to X-10. Z: -2 + H3 (90) = 88.
    tp = interpret(MASTERCAM, dialect=FANUC, tool_offsets={"H": {3: 90.0}, "D": {3: 4.0}})
    rows = [r for r in tp.to_records() if r["kind"] != "dwell"]
    cut = [r["end"][:2] for r in rows if r["kind"] == "line" and r["end"][2] == 88.0]
    assert cut == [[0.0, -10.0], [0.0, 4.0], [36.0, 4.0], [36.0, 26.0], [4.0, 26.0], [4.0, 0.0], [-10.0, 0.0]]
    assert rows[-1]["end"] == [0.0, 0.0, 0.0]  # G28 X0. Y0. (G91): via +0 to the reference position


def test_dialect_table_differences_are_data():
    fanuc, gsk = get_dialect(FANUC), get_dialect("gsk25i")
    # One family: the same expressions, variables, flow and calls; the lexer is the family's with the
    # least-unit reading of numbers without a decimal point (DPI = 0, lang/fanuc/least_units.py).
    assert (fanuc.language.runner, fanuc.language.variables, fanuc.language.system_variables) == (
        gsk.language.runner, gsk.language.variables, gsk.language.system_variables)
    assert issubclass(fanuc.language.reader, gsk.language.reader)
    assert fanuc.corner_words == {",C", ",R"} and gsk.corner_words == {",L", ",R"}
    assert not fanuc.compensation.length_needs_axis and gsk.compensation.length_needs_axis


# --------------------------------------------------------------------------- least input increments in G20
def test_a_number_without_a_point_counts_least_increments_of_the_unit_in_force():
    # Fanuc IS-B, DPI = 0: X1000 is 1000 × 0.001 mm = 1 mm in G21, 1000 × 0.0001 inch = 0.1 inch = 2.54 mm
    # in G20, whether G20 comes in the block, before it, or from the power-on setting.
    assert close(moves("G21 G00 X1000\n", dialect=FANUC)[0]["end"], [1.0, 0.0, 0.0])
    assert close(moves("G20 G00 X1000\n", dialect=FANUC)[0]["end"], [2.54, 0.0, 0.0])
    assert close(moves("G20\nG00 X1000 Y-2500\n", dialect=FANUC)[0]["end"], [2.54, -6.35, 0.0])
    assert close(moves("G00 X1000\n", dialect=FANUC, units="inch")[0]["end"], [2.54, 0.0, 0.0])
    # The unit is the one in force when the block runs: a subprogram read before its caller's G20 still
    # reads X1000 as 0.1 inch.
    sub = "G20\nM98 P1000\nM30\nO1000\nG00 X1000\nM99\n"
    assert close(moves(sub, dialect=FANUC)[0]["end"], [2.54, 0.0, 0.0])
    # Four decimals are 0.0001 inch in G20 (not cut to the metric 0.001 while the text is read).
    assert close(moves("G20 G00 X1.2345\n", dialect=FANUC)[0]["end"], [1.2345 * 25.4, 0.0, 0.0])
    # An arc's I/J count the same way: I1000 in G20 is a 0.1 inch radius.
    (arc,) = [r for r in moves("G20\nG02 X2000 Y0 I1000 F10.\n", dialect=FANUC) if r["kind"] == "arc"]
    assert close(arc["end"], [5.08, 0.0, 0.0]) and close(arc["radius"], 2.54)


def test_counts_and_times_are_not_lengths():
    # K (repeats) is a count: K3 is three holes, in G21 and G20; G04 X1500 is 1.5 s in either unit.
    for unit in ("G21", "G20"):
        holes = [r for r in moves(f"{unit}\nG91 G81 X10. Y0 Z-5. R-1. K3 F100.\n", dialect=FANUC)
                 if r["kind"] == "rapid" and r["start"][2] == r["end"][2]]  # fmt: skip  # positionings
        assert len(holes) == 3, unit
        (dwell,) = [r for r in interpret(f"{unit}\nG04 X1500\n", dialect=FANUC).to_records()]
        assert dwell["seconds"] == 1.5


def test_gsk25i_reads_a_number_without_a_point_in_the_unit_itself():
    # GSK 25i programming manual §1.7 with 1800#0 DPI = 1 (the standard setting): a value without a
    # decimal point is in mm or inch, so X10 in G20 is 10 inch; its least increment is 0.0001 in both.
    assert close(moves("G20 G00 X10\n")[0]["end"], [254.0, 0.0, 0.0])
    assert close(moves("G21 G00 X10\n")[0]["end"], [10.0, 0.0, 0.0])
    assert close(moves("G20 G00 X1.23456\n")[0]["end"], [1.2345 * 25.4, 0.0, 0.0])  # truncated
