"""Classes of reader input that once gave a traceback: each is one clean ``FILE:LINE: message [code]`` line
(exit 2 through ``cnc-gym trace``), in every dialect where the class applies.

* a letter that is no address of the dialect (the H4C-M has no E: ``E1``, ``END1``, an exponent ``X1e3``);
* a sign on a sequence number or another address without negative values (``N-0``, ``N+1`` on the H4C-M,
  whose labels are digit strings);
* a Unicode digit in a block that ends in ``;`` (the hint for ``G01 X1 ; comment`` re-read the parts after
  the illegal character had been found, and ``str.isdigit`` took '²').
"""

from __future__ import annotations

import pytest

from cnc_gym.cli import main
from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret

FAMILY = ("gsk25i", "fanuc", "syntec", "h4cm")
ALL = (*FAMILY, "azmc1")


def error_of(text: str, dialect: str) -> ProgramError:
    with pytest.raises(ProgramError) as info:
        interpret(text, dialect=dialect, file="part.nc")
    return info.value


@pytest.mark.parametrize("text", ["G01 X1 E1 F100\n", "END1\n", "G01 X1e3 F100\n", "E5;\n", "G01 X1E-3;\n",
                                  "N1 G01 X1. e2 F100\n"])  # fmt: skip
def test_a_letter_that_is_no_address_of_the_h4cm_is_unknown_address(text):
    err = error_of(text, "h4cm")
    assert (err.code, err.line, err.file) == ("unknown-address", 1, "part.nc")
    assert "E is not an address" in err.message


@pytest.mark.parametrize("text", ["N-0 G01 X1 F1\n", "N+1 G01 X1 F1\n", "N-0;\n", "N+12 G00 X1;\n",
                                  "N-0 M30\n", "N+1 G00 X#1\n"])  # fmt: skip
def test_a_signed_h4cm_label_is_bad_sign(text):
    err = error_of(text, "h4cm")
    assert (err.code, err.line) == ("bad-sign", 1)


@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc", "syntec", "h4cm"])
@pytest.mark.parametrize("text", ["N-0 G01 X1 F1\n", "G01 X1 F-0\n", "S-0 M3\n", "T-0\n", "G-0\n",
                                  "N-0 G00 X#1\n"])  # fmt: skip
def test_a_minus_sign_on_an_address_without_negative_values_is_bad_sign_even_on_zero(dialect, text):
    err = error_of(text, dialect)
    assert (err.code, err.line) == ("bad-sign", 1)


@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc", "syntec"])
@pytest.mark.parametrize("text", ["#1=²;\n", "/² G01 X1;\n", "GOTO²;\n", "#²=1;\n", "G01 X١;\n",
                                  "IF[1EQ1]GOTO²;\n", "WHILE[1EQ1]DO²;\n", "END²;\n", "G00 X[²];\n",
                                  "G01 X1 ; ² comment\n", "M98 P²;\n", "G65 P1 A²;\n"])  # fmt: skip
def test_a_unicode_digit_in_a_block_ending_in_a_semicolon_is_bad_character(dialect, text):
    err = error_of(text, dialect)
    assert (err.code, err.line) == ("bad-character", 1)


@pytest.mark.parametrize(("dialect", "text", "code"), [
    ("h4cm", "G01 X1 E1 F100\n", "unknown-address"),
    ("h4cm", "N+1 G01 X1 F1\n", "bad-sign"),
    ("gsk25i", "#1=²;\n", "bad-character"),
    ("fanuc", "/² G01 X1;\n", "bad-character"),
    ("syntec", "GOTO²;\n", "bad-character"),
])  # fmt: skip
def test_trace_reports_each_class_in_one_line(tmp_path, capsys, dialect, text, code):
    program = tmp_path / "bad.nc"
    program.write_text(text, encoding="utf-8")
    assert main(["trace", str(program), "--dialect", dialect]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"{program}:1: ") and captured.err.rstrip().endswith(f"[{code}]")
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err


@pytest.mark.parametrize("dialect", ALL)
@pytest.mark.parametrize("letter", ["A", "I", "X", "F", "P"])
def test_a_literal_too_long_for_a_float_is_one_clean_error(dialect, letter):
    """``float()`` of 400 digits is infinity: rounding it to the least increment once crashed the DIN
    reader (``G04 A1000…``, ``G43 I1000…``); it is an out-of-range or word-length error in every dialect."""
    text = f"G04 {letter}1{'0' * 400};\n" if dialect != "h4cm" else f"{letter}1{'0' * 60}\n"
    err = error_of(text, dialect)
    expected = {"value-out-of-range", "word-too-long", "unused-word", "block-too-long", "syntax"}
    assert err.line == 1 and err.code in expected


def test_rounding_to_an_increment_keeps_infinity_for_the_range_check():
    import math

    from cnc_gym.gcode.codes import round_to

    assert round_to(math.inf, 0.001) == math.inf and round_to(-math.inf, 0.001) == -math.inf
    assert math.isnan(round_to(math.nan, 0.001)) and round_to(1.23456, 0.001) == 1.235
