"""Expressions in [ ], # variables, null semantics and the GSK functions (§3.7.2).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import dataclasses
import math

import pytest
from gcode_helpers import close, moves, program_error

from cnc_gym.gcode import get_dialect

GSK = get_dialect("gsk25i")


def x_of(expression: str, setup: str = "") -> float:
    """The X end point of ``G00 X<expression>`` (machine = program: no offsets)."""
    return moves(f"{setup}G00 X{expression}\n")[0]["end"][0]


@pytest.mark.parametrize(
    ("expression", "expected"),
    [
        ("[1+2*3]", 7.0),  # * before + (§3.7.4)
        ("[[1+2]*3]", 9.0),
        ("[10-4-3]", 3.0),  # left to right
        ("[12/4/3]", 1.0),
        ("[-2*3]", -6.0),
        ("-[2+3]", -5.0),
        ("[7MOD3]", 1.0),
        ("[6AND3]", 2.0),  # 110 & 011
        ("[6OR3]", 7.0),
        ("[6XOR3]", 5.0),
        ("[1+6AND3]", 3.0),  # AND is multiplicative: 1 + (6 AND 3)
        ("[SIN[30]]", 0.5),  # degrees (§3.7.4)
        ("[COS[60]]", 0.5),
        ("[TAN[45]]", 1.0),
        ("[ATAN[1]]", 45.0),
        ("[ATAN[1]/[-1]]", 135.0),  # two-argument form, 0..360
        ("[ATAN[-1]/[-1]]", 225.0),
        ("[ASIN[0.5]]", 30.0),
        ("[ACOS[0.5]]", 60.0),
        ("[SQRT[2]*SQRT[2]]", 2.0),
        ("[ABS[-3.5]]", 3.5),
        ("[FIX[-1.7]]", -1.0),  # toward zero
        ("[FUP[-1.2]*10+FUP[1.2]]", -18.0),  # away from zero: -2*10 + 2
        ("[LN[EXP[2]]]", 2.0),
        ("[POW[2,10]]", 1024.0),
        ("[BCD[12]]", 18.0),  # decimal 12 → BCD 0001 0010 = 18
        ("[BIN[18]]", 12.0),
    ],
)
def test_expression_values(expression, expected):
    assert close(x_of(expression), expected, 1e-4)


def test_round_in_an_assignment_rounds_to_an_integer():
    # §3.7.4: in an operation command ROUND rounds to an integer, half away from zero
    # (ROUND[1.2345] = 1, ROUND[3.567] = 4). In an address it rounds to the address increment (below).
    assert x_of("#1", "#1=[ROUND[2.5]*100+ROUND[-2.5]*10+ROUND[1.2345]]\n") == 300 - 30 + 1
    assert x_of("#1", "#2=3.567\n#1=ROUND[#2]\n") == 4.0


def test_variables_assign_read_and_indirect():
    setup = "#1=3\n#100=[#1*2]\n#[#1+500]=7.5\n#2=#[503]\n"
    assert x_of("[#100+#2]", setup) == 13.5
    assert x_of("-#1", setup) == -3.0
    assert x_of("#2", setup) == 7.5


def test_assignment_blocks_may_carry_n_and_o():
    assert x_of("#2", "O1 N10 #1=5\nN20 #2=[#1*2]\n") == 10.0


def test_integer_literal_in_an_expression_is_a_plain_number():
    # "#1=133 gives 133.000" (§3.7.2); a constant without a point is read as if it had one (§3.7.4).
    assert x_of("#1", "#1=133\n") == 133.0


def test_null_variable_drops_the_word():
    # §3.7.2: with #1 = 0 and #2 null, "G00 X#1 Y#2" runs as "G00 X0".
    out = moves("G00 X5 Y5\n#1=0\nG00 X#1 Y#2\n")
    assert out[-1]["end"] == [0.0, 5.0, 0.0]
    # A sign on a bare null keeps it null: the word is still dropped.
    assert moves("G00 X5 Y5\nG00 X-#7 Y1\n")[-1]["end"] == [5.0, 1.0, 0.0]


def test_null_arithmetic_rules():
    # §3.7.2: #2=#1 keeps null; #1*5 and #1+#1 give 0.
    setup = "G00 X9\n#2=#1\n#3=[#1*5]\n#4=[#1+#1]\n"
    out = moves(setup + "G00 X#2\nG00 Y#3 Z#4\n")
    assert out[0]["end"] == [9.0, 0.0, 0.0]  # only the first block moves: X#2 dropped (null)
    assert len(out) == 1  # Y0 Z0 from the machine origin is no motion


def test_round_in_an_address_rounds_to_the_least_increment():
    # §3.7.4 (worked example X68) at the manual's 0.001 mm increment:
    #   N3 X#1 moves 1.235, N4 X#2 moves 2.346, N5 X-[#1+#2] moves -3.580, leaving 0.001 off the start;
    #   N5 X-[ROUND[#1]+ROUND[#2]] moves -3.581 and returns exactly.
    coarse = dataclasses.replace(GSK, least_increment_mm=0.001, least_increment_inch=0.001)
    head = "#1=1.2345\n#2=2.3456\nG91 G01 X#1 F100\nX#2\n"
    plain = moves(head + "X-[#1+#2]\n", dialect=coarse)
    assert [r["end"][0] for r in plain] == pytest.approx([1.235, 3.581, 0.001], abs=1e-9)
    fixed = moves(head + "X-[ROUND[#1]+ROUND[#2]]\n", dialect=coarse)
    assert fixed[-1]["end"][0] == pytest.approx(0.0, abs=1e-9)
    # At the default 0.0001 mm increment nothing is lost: 1.2345 + 2.3456 - 3.5801 = 0.
    assert moves(head + "X-[#1+#2]\n")[-1]["end"][0] == pytest.approx(0.0, abs=1e-9)


def test_g_code_from_a_variable():
    # "G#1" works (O9001 sample, §3.7.6).
    out = moves("#1=1\n#3=91\nG#1 G#3 X2 F100\nX2\n")
    assert [r["kind"] for r in out] == ["line", "line"] and out[-1]["end"][0] == 4.0


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("G00 X[1/0]\n", "division-by-zero", 208),
        ("#1=0\nG00 X[2/#1]\n", "division-by-zero", 208),
        ("G00 X[5MOD0]\n", "division-by-zero", 208),
        ("G00 X[SQRT[-1]]\n", "math-domain", None),
        ("G00 X[[[[[[1]]]]]]\n", "bracket-nesting", 209),  # 6 levels; the limit is 5 (§3.7.4)
        ("G00 X[1+]\n", "missing-operand", 207),
        ("G00 X[1+2\n", "bad-expression", 206),
        ("G00 X[FOO[1]]\n", "bad-expression", 206),
        ("G00 X[POW[2]]\n", "bad-expression", 206),
        ("#0=1\n", "bad-variable", 107),  # #0 is read-only (§3.7.2)
        ("#34=1\n", "bad-variable", 107),  # no such variable
        ("#1=2 X1\n", "bad-expression", 206),  # an assignment is alone in its block
        ("#4001=1\n", "read-only-variable", 107),  # system variables #4001-#5105 cannot be assigned (§3.7.3)
        ("#1=1\nIF[#1GT0]GOTO10\n", "sequence-not-found", 60),
        ("WHILE[#1LT3]DO1\n", "do-end", 96),  # DO1 without END1
        ("G01 X10 ,C5 F100\n", "bad-character", 9),  # GSK chamfers with ,L (§3.2.11), not Fanuc's ,C
        ("G00 X[1.5AND1]\n", "math-domain", None),
    ],
)
def test_expression_errors(text, code, alarm):
    err = program_error(text)
    assert (err.code, err.alarm) == (code, alarm)
    assert err.line == text.count("\n")


def test_pathological_expressions_are_errors_not_crashes():
    # Thousands of operators or signs must not reach Python's recursion limit.
    assert x_of("[" + "-" * 5001 + "3]") == -3.0
    assert x_of("[" + "+".join(["1"] * 150) + "]") == 150.0
    assert program_error("G00 X[" + "+".join(["1"] * 5000) + "]\n").code == "bad-expression"


def test_deep_but_legal_nesting():
    # Five levels, counting function brackets (§3.7.4): SIN[[[[x]]]] is 5.
    assert math.isclose(x_of("[SIN[[[[90]]]]]"), 1.0)


HUGE = "1" + "0" * 400  # a float of it is inf


@pytest.mark.parametrize(
    "text",
    [
        f"#{HUGE}=1\n",  # a variable number
        f"#1=#{HUGE}\n",
        f"GOTO{HUGE}\n",  # a GOTO target
        f"IF[#1GT0]GOTO{HUGE}\n",
        f"G00 X[{HUGE}]\n",  # an axis expression
        f"#1=[{HUGE}AND3]\n",  # AND / MOD operands
        f"#1=[3MOD{HUGE}]\n",
        f"G65 P9000 A[{HUGE}]\nM30\nO9000\nM99\n",  # a macro argument
        f"WHILE[1LT2]DO{HUGE}\nEND1\n",  # a loop identifier (int() of 4300+ digits is a ValueError)
        "#1=" + "9" * 5000 + "\n",
        "#1=123456789\n",  # 9 digits: beyond "max ±99999999"
    ],
)
def test_constants_have_at_most_8_digits(text):
    err = program_error(text)
    assert (err.code, err.alarm, err.line) == ("too-many-digits", 3, 1)


def test_8_digit_constants_and_long_decimals_are_fine():
    assert x_of("[99999999/10000000]") == pytest.approx(9.9999999)
    assert x_of("[000000001.5]") == 1.5  # leading zeros are no digits
    assert x_of("[3.14159265358979]") == 3.1416  # neither are decimals (ROUND to the increment)
    assert moves("#0000000001=2\nG01 X#1 F100\n")[0]["end"][0] == 2.0


@pytest.mark.parametrize("text", [f"G65 P{HUGE}\n", f"G65 P9000 A{HUGE}\nM30\nO9000\nM99\n", f"M98 P{HUGE}\n",
                                  f"G01 X{HUGE} F100\n", f"N{HUGE} G00 X1\n"])
def test_huge_literal_words_are_too_long(text):
    # As a word (not an expression), a 401-digit number is longer than the 16 characters of a word.
    err = program_error(text)
    assert (err.code, err.alarm, err.line) == ("word-too-long", 13, 1) and len(str(err)) < 600
