"""Lexical rules of the GSK 25i dialect (§1.2.3): %, O, N, comments, block skip, numbers, case.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import dataclasses

import pytest
from gcode_helpers import close, moves, program_error, records

from cnc_gym.gcode import get_dialect, interpret, read_program

GSK = get_dialect("gsk25i")


def test_percent_marks_o_and_n_numbers_are_not_motion():
    program = read_program("%\nO0001\nN10 G00 X1\nN20 X2\n%\nG01 X99 (after the end of tape: never read)\n")
    assert program.program_number == 1
    assert [b.number for b in program.blocks] == [None, 10, 20]
    assert program.sequence_index == {10: [1], 20: [2]}
    # The second '%' ends the tape: the G01 without F after it is not read, let alone executed.
    assert [r["end"][0] for r in moves("%\nO0001\nN10 G00 X1\nN20 X2\n%\nG01 X99\n")] == [1.0, 2.0]


def test_comments_case_spaces_and_semicolon_end_of_block():
    text = "g0 x 1 0 . 5 (a comment with X99 inside) y-2;  G 1 X  11 F 1 0 0 ; (whole-line comment)\n"
    out = moves(text)
    # Spaces are ignored inside numbers too (x 1 0 . 5 = X10.5); ';' separates two blocks on one line.
    assert [r["kind"] for r in out] == ["rapid", "line"]
    assert close(out[0]["end"], [10.5, -2.0, 0.0])
    assert close(out[1]["end"], [11.0, -2.0, 0.0]) and out[1]["feed"] == 100.0
    assert [r["line"] for r in out] == [1, 1]


def test_number_without_decimal_point_is_mm_and_literals_are_truncated():
    # GSK 1800#0 DPI = 1 (standard): X10 is 10 mm (§2.5). X9.87654 is truncated (not rounded) to the
    # least input increment 0.0001 mm: 9.8765 (§2.5, worked example X6).
    out = moves("G00 X10 Y9.87654 Z-0.00009\n")
    assert out[0]["end"] == [10.0, 9.8765, 0.0]  # -0.00009 truncates to -0.0000


def test_truncation_at_a_0_001_mm_increment_and_dpi_0():
    # The same literal at a 0.001 mm increment becomes 9.876 (§2.5, X6). With DPI = 0 a number without a
    # point counts least increments: X10000 = 10 mm at 0.001 mm (the Fanuc-style examples, §3.5.3).
    coarse = dataclasses.replace(GSK, least_increment_mm=0.001, least_increment_inch=0.001)
    assert moves("G00 X9.87654\n", dialect=coarse)[0]["end"][0] == 9.876
    dpi0 = dataclasses.replace(coarse, integer_is_unit=False)
    assert moves("G00 X10000 Y2.5 F1\n", dialect=dpi0)[0]["end"][:2] == [10.0, 2.5]


@pytest.mark.parametrize(
    ("switches", "expected_x"),
    [
        (frozenset(), [1.0, 2.0, 3.0, 4.0]),  # every switch off: all blocks run
        (frozenset({1}), [1.0, 4.0]),  # '/' = '/1' and '/1/3' both skipped
        (frozenset({3}), [1.0, 2.0, 4.0]),  # only the /1/3 block
        (frozenset({2}), [1.0, 2.0, 3.0, 4.0]),  # no block marked /2
    ],
)
def test_optional_block_skip(switches, expected_x):
    text = "G00 X1\n/X2\n/1/3 X3\nX4\n"
    assert [r["end"][0] for r in moves(text, block_skip=switches)] == expected_x


def test_block_skip_applies_to_program_end():
    # "/M30" does not end the program when the switch is on (§1.3.3).
    assert len(moves("G00 X1\n/M30\nX2\n", block_skip=frozenset({1}))) == 2
    assert len(moves("G00 X1\n/M30\nX2\n")) == 1


def test_slash_inside_a_block_discards_the_rest():
    # §1.3.4: "information between the slash and EOB code is ignored".
    assert moves("G00 X10 /Y20\n")[0]["end"] == [10.0, 0.0, 0.0]


def test_block_skip_syntax_errors():
    assert program_error("//3 G00 X10.0\n").code == "bad-block-skip"  # written /1/3 (§1.3.4)
    assert program_error("/0 G00 X1\n").code == "bad-block-skip"
    err = program_error("/#2 G00 X100.0\n")
    assert err.code == "variable-not-allowed"  # §3.7.2


def test_o_and_n_must_lead_the_block():
    assert program_error("G00 N10 X1\n").code == "misplaced-word"
    assert program_error("G00 X1 O12\n").code == "misplaced-word"
    assert program_error("N#3 Y200.0\n").code == "variable-not-allowed"  # §3.7.2
    assert program_error("O#1\n").code == "variable-not-allowed"  # §3.7.2


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("G01 X1.2.3 F100\n", "bad-number", 7),  # 7 ILLEGAL USE OF DECIMAL POINT
        ("G01 X1.23456.7 F100\n", "bad-number", 7),  # was truncated to X1.2345 silently
        ("G01 X-1.23456.7 Y#1 F100\n", "bad-number", 7),  # the scanner's path
        ("G05 P10000\nG06.2 P2 K1.2345. X0 Y0 F100\n", "bad-number", 7),  # G06.2's own K format
        ("G05 P10000\nG06.2 P2 K0 X0 Y0 F100\nK1.2345. X1\n", "bad-number", 7),  # a ValueError
        ("G110 X1 L2.55555.5\n", "bad-number", 7),  # a cycle's own L format
        ("G01 X. F100\n", "bad-number", 7),
        ("G01 X F100\n", "missing-value", 5),
        ("G01 X- F100\n", "bad-sign", 6),  # 6 ILLEGAL USE OF NEGATIVE SIGN
        ("G01 X1-2 F100\n", "bad-sign", 6),
        ("123\n", "missing-address", 4),  # 4 ADDRESS NOT FOUND
        ("G01 X10 F100 $\n", "bad-character", 9),
        ("G01 X10 F100 (unclosed\n", "unclosed-comment", None),
        ("G01 X10 F100 )\n", "bad-character", 9),
        ("G00 X1 % \n", "bad-character", 9),
        ("%G01 X1\n", "bad-character", 9),  # the tape mark's own check named no file
        ("M3.5\n", "decimal-point-not-allowed", 7),
        ("T1.0\n", "decimal-point-not-allowed", 7),
        ("N1234567 G00 X1\n", "value-out-of-range", 16),
        ("S99999\n", "value-out-of-range", 200),
        ("G01 X1 F-100\n", "bad-sign", 6),
        ("G00 X1000000\n", "value-out-of-range", 8),
    ],
)
def test_lexical_errors(text, code, alarm):
    err = program_error(text, file="part.nc")
    assert (err.code, err.alarm, err.file, err.line) == (code, alarm, "part.nc", text.count("\n"))


def test_error_line_counts_blank_and_comment_lines():
    err = program_error("\n(header)\n\nG00 X1\nG01 X1.2.3\n", file="p.nc")
    assert err.line == 5
    assert str(err).startswith("p.nc:5: ") and str(err).endswith("[bad-number]")


def test_lowercase_and_uppercase_give_the_same_toolpath():
    text = "G17 G90 G01 X12.5 Y-3 F250\nG02 X20 Y4.5 R8\nM30\n"
    assert records(text) == records(text.lower())


def test_two_words_of_one_address_are_an_error():
    # The manual's default is "the later one is valid" (§1.3.2); this interpreter raises instead
    # (1802#6 AD2 = 1 behaviour), consistently with group conflicts. docs/gcode.md.
    assert program_error("G01 X1 X2 F100\n").code == "duplicate-word"


def test_interpret_keeps_the_file_name_in_the_toolpath():
    tp = interpret("G00 X1\n", file="dir/part.nc")
    assert tp.files[0] == "dir/part.nc"


@pytest.mark.parametrize(
    ("text", "char"),
    [
        ("#1=²\n", "²"),  # a superscript passes str.isdigit
        ("#²=1\n", "²"),
        ("G01 X١٢ F100\n", "١"),  # Arabic-Indic digits were silently read as 12
        ("#1=١٢\nG01 X#1 F100\n", "١"),
        ("G01 X1.5 F１00\n", "１"),  # a fullwidth digit
        ("G01 Xı F100\n", "ı"),  # 'ı'.upper() is the ASCII 'I'
        ("G0ﬁ\n", "ﬁ"),  # 'ﬁ'.upper() is 'FI'
        ("G01 X1 F100\u00a0Y2\n", "\u00a0"),  # a no-break space is not a space
        ("G01 X1 F100\u2028Y2\n", "\u2028"),  # nor a line break
    ],
)
def test_only_ascii_is_program_text(text, char):
    # Only ASCII letters and digits are program text: anything else is alarm 9 ILLEGAL CHARACTERS.
    err = program_error(text, file="part.nc")
    assert (err.code, err.alarm, err.line) == ("bad-character", 9, 1)
    assert repr(char) in err.message


def test_comments_may_hold_any_text_and_lines_break_at_cr_or_lf_only():
    assert len(records("G00 X1 (Maß ½ – ok)\r\nG00 X2\rG00 X3\n")) == 3
    # FS, NEL and U+2029 are no line breaks (str.splitlines would split there): an editor's line numbers.
    err = program_error("G00 X1\nG00 X2\x1cG00 X3\nG00 X4\u2029\n")
    assert (err.code, err.line) == ("bad-character", 2)


@pytest.mark.parametrize(
    ("text", "code"),
    [
        ("G01 " + "X1" * 3_000_000 + "\n", "too-many-words"),  # 6 MB: the plain-block regex kept 600 MB
        ("G01 " + "X1\t" * 2_000_000 + "\n", "too-many-words"),  # re.sub of the blanks kept 160 MB
        ("G65 P1 " + "A1 " * 1_000_000 + "\n", "too-many-words"),  # a call block's arguments
        ("#1=" + "1+" * 1_000_000 + "1\n", "bad-expression"),  # more than 200 operators
    ],
)
def test_one_long_line_is_an_error_in_bounded_memory(text, code):
    import tracemalloc

    tracemalloc.start()
    try:
        err = program_error(text)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert err.code == code and err.line == 1
    assert peak < 8 * len(text) + 2**20  # a few copies of the line, not an object per word
