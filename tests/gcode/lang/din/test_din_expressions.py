"""The DIN family's expression language: every operator and function, precedence, truth, the sign rule,
and the errors (AMK AZ-MC1 programming manual §2.4.1, §9.1.1). Expected values are worked out by hand."""

from __future__ import annotations

import math

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import get_dialect, interpret
from cnc_gym.gcode.lang.din.expressions import FUNCTIONS, Parser, truth, value
from cnc_gym.gcode.lang.din.parameters import ParameterStore


def calc(text: str, **params: float) -> float:
    """The value of ``text`` with the given R parameters (``R3=2`` as ``calc("R3*2", R3=2)``)."""
    store = ParameterStore()
    for name, v in params.items():
        store[int(name[1:])] = v
    parser = Parser(text.upper(), FUNCTIONS)
    fn = parser.expression()
    assert parser.at_end(), f"unread: {text[parser.pos:]!r}"
    return value(fn, store)


@pytest.mark.parametrize(("text", "expected"), [
    ("2 + 3", 5), ("2 - 3", -1), ("2 * 3", 6), ("7 / 2", 3.5), ("2**3", 8), ("11 MOD 3", 2),
    ("-7 MOD 3", -1),  # C's fmod: the sign of the dividend
    ("7.5 MOD 2", 1.5),
    ("1 == 1", 1), ("1 == 2", 0), ("1 != 2", 1), ("1 != 1", 0), ("2 >= 2", 1), ("1 >= 2", 0),
    ("2 <= 2", 1), ("3 <= 2", 0), ("1 < 2", 1), ("2 < 2", 0), ("3 > 2", 1), ("2 > 2", 0),
])  # fmt: skip
def test_each_operator(text, expected):
    assert calc(text) == expected


@pytest.mark.parametrize(("text", "expected"), [
    ("ABS[-2.5]", 2.5), ("SQR[3]", 9), ("SQRT[16]", 4), ("SQRT[0]", 0), ("EXP[1]", math.e), ("LN[1]", 0),
    ("DEXP[2]", 100), ("LOG[1000]", 3), ("SIN[30]", 0.5), ("COS[60]", 0.5), ("TAN[45]", 1),
    ("ASIN[0.5]", 30), ("ACOS[0.5]", 60), ("ATAN[1]", 45), ("INT[2.7]", 2), ("INT[-2.7]", -2),
    ("FRACT[2.75]", 0.75), ("FRACT[-2.75]", -0.75),
])  # fmt: skip
def test_each_function_in_degrees(text, expected):
    assert calc(text) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(("text", "expected"), [
    ("2 + 3 * 4", 14),  # dot before dash
    ("[2 + 3] * 4", 20),  # the brackets rule
    ("2 * 3 ** 2", 18),  # ** above *
    ("2 ** 3 ** 2", 512),  # right-associative
    ("-2 ** 2", -4),  # the sign applies to the power
    ("10 - 4 - 3", 3),  # left-associative
    ("12 / 3 / 2", 2),
    ("1 + 1 == 2", 1),  # comparisons last
    ("10 MOD 4 * 2", 4),  # MOD with * and /, left to right: (10 MOD 4) * 2
    ("[-5] * 2", -10),
    ("+5", 5),
])  # fmt: skip
def test_precedence_and_grouping(text, expected):
    assert calc(text) == expected


def test_parameters_direct_computed_and_indirect():
    assert calc("R1 + R2", R1=1.5, R2=2) == 3.5
    assert calc("R[R1 + 1]", R1=4, R5=9) == 9  # R[e]: the parameter numbered e
    assert calc("P10", R10=20, R20=7) == 7  # P10: the parameter whose number R10 holds
    assert calc("100 + SIN [R10 + P20]", R10=20, R20=3, R3=10) == pytest.approx(100.5)


def test_truth_is_magnitude_at_least_one_half():
    assert [truth(v) for v in (0.49, 0.5, -0.5, -0.49, 0.0, 3.0)] == [False, True, True, False, False, True]


@pytest.mark.parametrize(("text", "message"), [
    ("1 / 0", "division by zero"), ("1 MOD 0", "MOD by zero"), ("SQRT[-1]", "not be negative"),
    ("LN[0]", "greater than 0"), ("LOG[-1]", "greater than 0"), ("ASIN[2]", "-1 .. +1"),
    ("ACOS[-1.5]", "-1 .. +1"), ("TAN[90]", "does not exist"), ("TAN[270]", "does not exist"),
    ("[-8] ** 0.5", "not a real number"), ("10 ** 400", "overflows"), ("EXP[1000]", "overflows"),
    ("R[1.5]", "whole numbers"), ("R[-1]", "whole numbers"),
])  # fmt: skip
def test_math_errors_are_program_errors(text, message):
    with pytest.raises(ProgramError, match=message.replace("+", r"\+").replace(".", r"\.")) as info:
        calc(text)
    assert info.value.code in ("math-error", "bad-parameter")


@pytest.mark.parametrize(("text", "message"), [
    ("R1 >= -5", "must be bracketed"), ("2 * -3", "must be bracketed"), ("2 + +3", "must be bracketed"),
    ("SIN 30", "expected '\\['"), ("[1 + 2", "expected '\\]'"), ("FOO[1]", "unknown function"),
    ("R10000", "parameters are numbered"), ("R1.5", "whole number"), ("P[1]", "P takes a parameter number"),
    ("2 +", "expected a number"),
])  # fmt: skip
def test_syntax_errors_name_the_problem(text, message):
    with pytest.raises(ProgramError, match=message) as info:
        calc(text)
    assert info.value.code == "syntax" and info.value.column is not None


def test_expressions_end_where_the_grammar_ends():
    # After an operand the expression goes on only over a binary operator: "1.5 Y R1" ends at Y.
    parser = Parser("R1 - 1.5 Y R1", FUNCTIONS)
    parser.expression()
    assert parser.text[parser.pos:].strip() == "Y R1"
    parser = Parser("10 MOD 3 M03", FUNCTIONS)
    parser.expression()
    assert parser.text[parser.pos:].strip() == "M03"


def test_values_in_programs_round_to_the_resolution():
    # Lengths are rounded to 0.1 µm (§2.7): X 1/3 is 0.3333.
    toolpath = interpret("G1 F100 X 1/3 Y [2/3]\nM30\n", dialect=get_dialect("azmc1"))
    assert toolpath.end[0].tolist()[:2] == pytest.approx([0.3333, 0.6667], abs=1e-12)
