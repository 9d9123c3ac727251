"""Macro B control flow (§3.7.2, §3.7.4-§3.7.5).

Expected values are worked out by hand from the manual's rules; each test says how.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import dataclasses
import time

import pytest
from gcode_helpers import close, moves, program_error

from cnc_gym.errors import ConfigError
from cnc_gym.gcode import get_dialect, interpret


def ends(text: str, **kw) -> list[tuple[float, ...]]:
    return [tuple(round(v, 6) for v in r["end"]) for r in moves(text, **kw)]


def x_values(text: str, **kw) -> list[float]:
    return [round(r["end"][0], 6) for r in moves(text, **kw)]


# --------------------------------------------------------------------------- null semantics (§3.7.2)
@pytest.mark.parametrize(
    ("setup", "condition", "expected"),
    [
        # The manual's table: #1 vacant vs #1 = 0.
        ("", "#1EQ#0", True), ("#1=0", "#1EQ#0", False),
        ("", "#1NE0", True), ("#1=0", "#1NE0", False),
        ("", "#1GE#0", True), ("#1=0", "#1GE#0", True),
        ("", "#1GT0", False), ("#1=0", "#1GT0", False),
        # GT/GE/LT/LE read null as 0 on either side.
        ("", "#1LT1", True), ("", "#1LE0", True), ("", "0LT#1", False),
        # Null equals only null.
        ("", "#0EQ#0", True), ("", "#1EQ#2", True), ("#2=0", "#1EQ#2", False),
    ],
)  # fmt: skip
def test_conditions_tell_null_from_zero_only_in_eq_ne(setup, condition, expected):
    # IF[…]THEN sets #5 only when the condition holds; X#5 then moves (X1) or is dropped (null).
    text = f"{setup}\nIF[{condition}]THEN#5=1\nG00 X#5 Y2\n"
    assert ends(text) == [(1.0, 2.0, 0.0) if expected else (0.0, 2.0, 0.0)]


def test_null_propagation_in_assignment_and_arithmetic():
    # #2=#1 keeps null (the X word is dropped); #1*5 and #1+#1 are 0 (§3.7.2).
    text = "#2=#1\n#3=#1*5\n#4=#1+#1\nIF[#2EQ#0]THEN#10=1\nIF[#3EQ0]THEN#11=1\nIF[#4EQ0]THEN#12=1\n" \
           "G00 X#10 Y#11 Z#12\n"  # fmt: skip
    assert ends(text) == [(1.0, 1.0, 1.0)]


# --------------------------------------------------------------------------- operators and functions
@pytest.mark.parametrize(
    ("expression", "value"),
    [
        ("1+2*3", 7.0),  # * binds tighter than + (§3.7.4)
        ("[1+2]*3", 9.0),
        ("2OR1AND3", 3.0),  # AND is multiplicative: 2 OR (1 AND 3) = 2 | 1 = 3
        ("6XOR3", 5.0),  # 110 ^ 011 = 101
        ("12AND10", 8.0),  # 1100 & 1010 = 1000
        ("7MOD3", 1.0),
        ("10-4-3", 3.0),  # left to right
        ("SIN[30]", 0.5),  # degrees
        ("COS[60]+TAN[45]", 1.5),
        ("ATAN[1]/[1]", 45.0),  # two-argument form
        ("ATAN[-1]/[-1]", 225.0),  # 0..360 degrees
        ("SQRT[16]+ABS[-2]", 6.0),
        ("ROUND[1.5]+ROUND[-1.5]", 0.0),  # half away from zero: 2 + (-2)
        ("FIX[1.7]+FIX[-1.7]", 0.0),  # truncation toward zero: 1 + (-1)
        ("FUP[1.2]", 2.0), ("FUP[-1.2]", -2.0),  # away from zero
        ("BCD[25]", 37.0),  # 25 → 0010 0101 = 0x25 = 37
        ("BIN[37]", 25.0),  # back
        ("SIN[[[[1]]]]*0+1", 1.0),  # five levels of brackets including the function's own
    ],
)  # fmt: skip
def test_operators_and_functions(expression, value):
    assert close(x_values(f"#1={expression}\nG00 X#1\n") or [0.0], [value])


def test_bracket_nesting_beyond_five_levels_is_alarm_209():
    err = program_error("#1=SIN[[[[[[1]]]]]]\n")  # SIN's bracket + 5 more = 6 levels
    assert err.code == "bracket-nesting" and err.alarm == 209


def test_values_beyond_1e47_overflow_alarm_102():
    # §3.7.7: variables hold at most ±10^47; 1E42 * 1E7 does not fit. (Constants have at most 8 digits,
    # §3.7.4: 10000000 is 1E7.)
    err = program_error("#1=10000000*10000000*10000000*10000000*10000000*10000000*10000000\n")
    assert (err.code, err.alarm) == ("overflow", 102)
    assert x_values("#1=10000000*10000000*10000000*10000000*10000000*10000000\nG00 X[#1/#1]\n") == [1.0]


def test_roundoff_example_x68_with_a_0_001_increment():
    # §3.7.4 (example X68) on a 0.001 mm controller: each variable is rounded to the address's increment
    # when used, so N3 moves 1.235 and N4 2.346 but N5 moves -3.580 (#1+#2 = 3.5801 → 3.580): the tool ends
    # 0.001 from the start; with ROUND on each term it returns exactly (-[1.235 + 2.346] = -3.581).
    coarse = dataclasses.replace(get_dialect("gsk25i"), least_increment_mm=0.001)
    program = "N1 #1=1.2345\nN2 #2=2.3456\nG91\nN3 G01 X#1 F100\nN4 X#2\nN5 X-[{}]\n"
    plain = x_values(program.format("#1+#2"), dialect=coarse)
    assert close(plain, [1.235, 3.581, 0.001])
    fixed = x_values(program.format("ROUND[#1]+ROUND[#2]"), dialect=coarse)
    assert close(fixed, [1.235, 3.581, 0.0])


def test_round_in_a_condition_rounds_to_an_integer():
    # §3.7.4: IF[#1 LE ROUND[#2]] with #2 = 3.567 compares with 4.0.
    assert ends("#1=3.9\n#2=3.567\nIF[#1LEROUND[#2]]THEN#3=1\nG00 X#3\n") == [(1.0, 0.0, 0.0)]


def test_comparisons_allow_eight_digit_roundoff():
    # 0.1 added ten times is 0.9999999999999999 in binary; the controller (8 digits) calls that 1, so the
    # loop "WHILE[#1 LE 1]" with step 0.1 runs 11 times (0.0 … 1.0) and EQ finds 1.
    text = ("#1=0\n#2=0\nWHILE[#1LE1]DO1\n#2=#2+1\n#1=#1+0.1\nEND1\n#1=0\n#3=0\nWHILE[#3LT10]DO1\n"
            "#1=#1+0.1\n#3=#3+1\nEND1\nIF[#1EQ1]THEN#4=1\nG00 X#2 Y#4\n")  # fmt: skip
    assert ends(text) == [(11.0, 1.0, 0.0)]


# --------------------------------------------------------------------------- WHILE / DO / END
def test_while_loop_x70():
    # §3.7.5: #120 runs 1..10; each pass moves X to #120: ten moves X1 … X10.
    text = "#120=1\nN1 WHILE[#120LE10]DO1\nG01 X#120 F100\n#120=#120+1\nN4 END1\nM30\n"
    assert x_values(text) == [float(i) for i in range(1, 11)]


def test_false_condition_skips_the_loop_body():
    assert ends("WHILE[1GT2]DO1\nG00 X5\nEND1\nG00 Y1\n") == [(0.0, 1.0, 0.0)]


def test_three_nested_loops_and_reused_identifiers():
    # 2 x 2 x 2 passes of the innermost move, then DO1 reused in sequence (rule ③) for 3 more.
    text = """#1=0
#10=0
WHILE[#1LT2]DO1
#2=0
WHILE[#2LT2]DO2
#3=0
WHILE[#3LT2]DO3
#10=#10+1
G01 X#10 F100
#3=#3+1
END3
#2=#2+1
END2
#1=#1+1
END1
#1=0
WHILE[#1LT3]DO1
#10=#10+1
G01 X#10
#1=#1+1
END1
"""
    assert x_values(text) == [float(i) for i in range(1, 12)]


def test_do_without_while_loops_until_a_goto_leaves():
    # §3.7.5: DOm without WHILE repeats forever; GOTO out of the range is allowed (rule ⑥).
    text = "#1=0\nDO1\n#1=#1+1\nG01 X#1 F100\nIF[#1GE3]GOTO9\nEND1\nN9 G00 Y1\n"
    assert ends(text) == [(1.0, 0.0, 0.0), (2.0, 0.0, 0.0), (3.0, 0.0, 0.0), (3.0, 1.0, 0.0)]


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("DO1\nDO2\nDO3\nDO1\nEND1\nEND3\nEND2\nEND1\n", "DO1 inside DO1"),
        ("WHILE[1LT2]DO1\nWHILE[1LT2]DO2\nWHILE[1LT2]DO3\nDO3\n", "four levels"),  # DO3 again
        ("DO1\nDO2\nEND1\nEND2\n", "crossing (rule ⑤)"),
        ("END1\nDO1\nEND1\n", "END before DO (rule ①)"),
        ("DO1\nG00 X1\n", "DO without END"),
        ("GOTO5\nDO1\nN5 G00 X1\nEND1\n", "GOTO into a DO range (rule ⑦)"),
        ("GOTO9\nDO1\nN5 G00 X1\nEND1\nN9 DO2\nGOTO5\nEND2\n", "GOTO into another DO range"),
        ("DO4\nEND4\n", "identifier 1..3"),
        ("WHILE[1LT2]DO0\nEND0\n", "identifier 1..3"),
    ],
)  # fmt: skip
def test_do_end_errors_are_alarm_96(text, why):
    err = program_error(text)
    # An identifier outside 1..3 is alarm 97 ILLEGAL CYCLE NUMBER, the pairing errors 96 (alarm list).
    assert (err.code, err.alarm) == ("do-end", 97 if why == "identifier 1..3" else 96), why


def test_four_levels_of_do_is_alarm_96_at_the_fourth():
    text = "WHILE[1LT2]DO1\nWHILE[1LT2]DO2\nWHILE[1LT2]DO3\nWHILE[1LT2]DO1\nEND1\nEND3\nEND2\nEND1\n"
    err = program_error(text)
    assert err.alarm == 96 and err.line == 4


def test_loops_are_checked_when_the_program_is_entered_not_when_reached():
    # A DO without END is a structure error even in a part of the program the run never reaches.
    err = program_error("G00 X1\nM30\nDO1\n")
    assert err.code == "do-end" and err.line == 3


def test_a_callee_may_nest_three_more_levels():
    # Rule ⑧: inside DO1-DO3 of the main program, a subprogram nests its own three levels.
    text = """WHILE[#100LT1]DO1
WHILE[#101LT1]DO2
WHILE[#102LT1]DO3
M98 P10
#100=1
#101=1
#102=1
END3
END2
END1
M30
O10
WHILE[#110LT1]DO1
WHILE[#111LT1]DO2
WHILE[#112LT1]DO3
G00 X7
#110=1
#111=1
#112=1
END3
END2
END1
M99
"""
    assert ends(text) == [(7.0, 0.0, 0.0)]


# --------------------------------------------------------------------------- GOTO and IF
def test_goto_skips_forward_and_searches_backward():
    # GOTO searches forward from the next block, then wraps to the start (inferred from §1.2.3).
    text = "#1=0\nN10 #1=#1+1\nIF[#1GE3]GOTO30\nGOTO10\nG00 X99\nN30 G00 X#1\n"
    assert ends(text) == [(3.0, 0.0, 0.0)]


def test_goto_picks_the_first_match_forward_then_wraps_for_duplicates():
    # Two N5 blocks: from the GOTO at line 2 the next N5 forward is line 4 (X2), not line 1.
    text = "N5 #1=#1+1\nIF[#1LT2]GOTO5\nG00 X1\nN5 G00 X[2*#1]\n"
    # Pass 1: #1=1 → GOTO5 forward hits line 4: X2. End of program.
    assert ends(text) == [(2.0, 0.0, 0.0)]


def test_computed_goto():
    # GOTO#i and GOTO[expression] (§3.7.5).
    text = "#1=20\nGOTO#1\nN10 G00 X10\nN20 G00 Y20\nGOTO[#1+10]\nN25 G00 Z99\nN30 G00 Z30\n"
    assert ends(text) == [(0.0, 20.0, 0.0), (0.0, 20.0, 30.0)]


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("GOTO77\n", "sequence-not-found", 60),
        ("GOTO#1\n", "sequence-not-found", 60),  # null target
        ("#1=2.5\nGOTO#1\n", "sequence-not-found", 60),
        ("IF[#1]GOTO5\n", "bad-expression", 206),  # no comparison: a malformed expression
        ("IF[#1EQ1+]GOTO5\n", "missing-operand", 207),
        # Malformed statements: ILLEGAL MACRO PROGRAM COMMAND.
        ("IF[#1EQ1]\n", "bad-macro-command", 205),
        ("IF#1EQ1GOTO5\n", "bad-macro-command", 205),
        ("G00 X1 GOTO5\n", "bad-macro-command", 205),  # a statement is alone in its block
        ("GOTO5 X1\n", "bad-macro-command", 205),
        ("THEN#1=1\n", "bad-macro-command", 205),
        ("WHILE[1LT2]\n", "bad-macro-command", 205),
        ("IF[1LT2]THENG00X1\n", "bad-macro-command", 205),  # THEN takes an assignment only
    ],
)  # fmt: skip
def test_statement_errors(text, code, alarm):
    err = program_error(text)
    assert (err.code, err.alarm) == (code, alarm)


def test_user_alarm_x69_names_the_alarm_and_message():
    # §3.7.5: with #1 >= 10 the jump reaches N150 #3000=150: alarm 3150 with the comment as message.
    text = "#1=12\nIF[#1GE10]GOTO150\nG00 X1\nM99\nN150 #3000=150 (RANGE ERROR)\nM99\n"
    err = program_error(text)
    assert err.code == "user-alarm" and err.alarm == 3150 and err.line == 5 and "RANGE ERROR" in err.message
    # Below 10 the program ends at M99 (one pass of the main program) after X1.
    assert ends(text.replace("#1=12", "#1=5")) == [(1.0, 0.0, 0.0)]


def test_if_then_assigns_only_when_true():
    assert ends("#1=5\nIF[#1GT3]THEN#2=#1*2\nIF[#1GT9]THEN#3=1\nG00 X#2 Y#3\n") == [(10.0, 0.0, 0.0)]


def test_keywords_with_spaces_and_lower_case():
    text = ("#1 = 0\nwhile [#1 lt 2] do 1\n#1 = #1 + 1\ng01 x#1 f100\nend 1\nif [#1 eq 2] goto 7\ng00 y5\n"
            "n7 g00 z1\n")  # fmt: skip
    assert ends(text) == [(1.0, 0.0, 0.0), (2.0, 0.0, 0.0), (2.0, 0.0, 1.0)]


# --------------------------------------------------------------------------- bounds
def test_runaway_goto_loop_ends_with_a_clear_error():
    err = program_error("N1 G91 G01 X1 F100\nGOTO1\n", max_blocks=500)
    assert err.code == "too-many-blocks" and "500" in err.message


def test_runaway_do_loop_ends_with_a_clear_error():
    err = program_error("DO1\n#1=#1+1\nEND1\n", max_blocks=1000)
    assert err.code == "too-many-blocks"


def test_max_blocks_counts_executed_blocks():
    # 1 + 3 x (WHILE, move, increment, END) + the final failing WHILE = 14 blocks: 14 runs, 13 does not.
    text = "#1=0\nWHILE[#1LT3]DO1\nG01 X#1 F100\n#1=#1+1\nEND1\n"
    assert len(interpret(text, max_blocks=14)) == 2  # X0 is no move
    assert program_error(text, max_blocks=13).code == "too-many-blocks"


@pytest.mark.parametrize("bad", [0, -1, 2.5, True, "10"])
def test_max_blocks_must_be_a_positive_integer(bad):
    from cnc_gym.errors import ConfigError

    with pytest.raises(ConfigError):
        interpret("G00 X1\n", max_blocks=bad)


# A loop that never ends but stays within the block budget for long: 2 000 000 blocks take seconds.
_ENDLESS = "#1=0\nWHILE[#1LT1]DO1\nG91 G01 X1 F100\nX-1\nEND1\n"


def test_interpretation_time_is_bounded():
    start = time.process_time()
    err = program_error(_ENDLESS, max_seconds=0.3)
    assert (err.code, err.alarm) == ("time-budget", None) and "max_seconds" in err.message
    assert err.line in (2, 5)  # the WHILE or the END (where control leaves the straight path)
    assert time.process_time() - start < 3.0


def test_tool_path_size_is_bounded():
    err = program_error(_ENDLESS, max_segments=5000)
    assert err.code == "segment-budget" and "5000" in err.message
    # A single cycle block makes its moves under the same bounds (checked per hole).
    err = program_error("G91 G81 X1 Z-1 R1 F100 K50000\n", max_segments=5000)
    assert (err.code, err.line) == ("segment-budget", 1)
    assert program_error("G91 G81 X1 Z-1 R1 F100 K99999\n", max_seconds=0.05).code == "time-budget"
    # A subprogram that ends without M99 returns at the end of its text: checked there too, with its line.
    err = program_error("M98 P1 L9999\nM30\nO1\nG91 G01 X1 F100\nX-1\n", max_segments=1000, file="p.nc")
    assert (err.code, err.file, err.line) == ("segment-budget", "p.nc", 5)


@pytest.mark.parametrize(("name", "bad"), [("max_seconds", 0), ("max_seconds", float("nan")),
                                           ("max_seconds", "5"), ("max_segments", 0), ("max_segments", 1.5),
                                           ("max_segments", True)])
def test_bad_bounds_are_config_errors(name, bad):
    with pytest.raises(ConfigError, match=name):
        interpret("G00 X1\n", **{name: bad})
