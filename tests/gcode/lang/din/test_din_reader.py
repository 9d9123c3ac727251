"""The DIN family's lexer, control blocks and calls (AMK AZ-MC1 programming manual §2, §7, §9): what reads,
and every syntax or structure error with its message, file, line (and column where the reader knows it)."""

from __future__ import annotations

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret, read_program


def run(text: str, **kw):
    return interpret(text, dialect="azmc1", file=kw.pop("file", "p.din"), **kw)


def ends(text: str, **kw) -> list[tuple]:
    return [tuple(round(c, 4) + 0.0 for c in row) for row in run(text, **kw).end.tolist()]


def error(text: str, **kw) -> ProgramError:
    with pytest.raises(ProgramError) as info:
        run(text, **kw)
    return info.value


# ---------------------------------------------------------------------- lexer
def test_words_numbers_case_and_blanks():
    # No implied decimal point (X1 is 1 mm), blanks between address and value, lower case, + signs,
    # leading and trailing decimal points, words glued without blanks.
    assert ends("g1 x1 f100\nX 2.5 Y+3 Z-.5\nG1X10.Y20\nM30\n") == [(1, 0, 0), (2.5, 3, -0.5), (10, 20, -0.5)]


def test_comments_nest_and_end_at_the_end_of_the_line():
    text = "G1 X1 F100 (a (nested) comment) Y2\nG1 X3 (unclosed (comment\nM30\n"
    assert ends(text) == [(1, 2, 0), (3, 2, 0)]


def test_block_skip_and_numbers():
    toolpath = run("/N10 G1 X5 F100\nN10 G1 Y5 F100\nN5 X1\nM30\n", block_skip=frozenset({1}))
    assert toolpath.end.tolist() == [[0, 5, 0], [1, 5, 0]]  # skipped, then N10 and N5 (any order)
    assert ends("/N10 G1 X5 F100\nM30\n") == [(5, 0, 0)]  # the switch off: the block runs


def test_program_headers_and_units():
    text = "%L7\nG1 X1 F100\nM29\n%L008 (second)\nX2\n% 100 (main)\nLL7\nM30\n"
    program = read_program(text, dialect="azmc1")
    assert program.program_number == 100 and program.local_units == {7: (0, 2), 8: (2, 3)}
    assert program.main == (3, 5)


SYNTAX = [
    # (program, line, code, message fragment)
    ("G1 F100\nX50R1=7\n", 2, "syntax", "separated from the word before it by a blank"),
    ("$ IF R1\n$ENDIF\n", 1, "syntax", "no blank between $ and the keyword"),
    ("$GOTO 10\n", 1, "syntax", "unknown control statement $GOTO"),
    ("R1 = 1\n$IF R1 G1 X1\n$ENDIF\n", 2, "syntax", "holds nothing else"),
    ("G1 X1 $IF R1\n", 1, "syntax", "stands alone in its block"),
    ("%100\nM30\n%L5\nM29\n", 3, "program-structure", "stand before the main program"),
    ("G1 X1 F100\n%L5\nM29\n", 2, "program-structure", "blocks before the first % header"),
    ("%L5\nM29\n", 1, "program-structure", "no main program"),
    ("%100\n%200\n", 2, "program-structure", "a second main program header"),
    ("%L5\nM29\n%L5\nM29\n%1\n", 3, "program-structure", "defined twice"),
    ("%ABC\n", 1, "syntax", "bad program header"),
    ("%123456789\n", 1, "syntax", "at most 8 digits"),
    ("%L\n", 1, "syntax", "%L needs the subroutine's number"),
    ("O10\n", 1, "unknown-address", "unknown address O"),
    ("G1.5 X1\n", 1, "syntax", "G takes a whole number"),
    ("G R1\n", 1, "syntax", "G takes a literal whole number"),
    ("G1 F100 X\n", 1, "syntax", "address X needs a value"),
    ("R1 =\n", 1, "syntax", "needs a value"),
    ("G1 X1 X2 F100\n", 1, "duplicate-word", "address X appears twice"),
    ("G1 X1 F100)\n", 1, "syntax", "')' without '('"),
    ("G1 X1 F100 (Größe)\n", 1, "bad-character", "ASCII character set"),
    ("N10 N20 G1\n", 1, "syntax", "N (the block number) begins the block"),
    ("G2 X10 Y0 R5 F100\n", 1, "syntax", "R is a parameter, not an address"),
    ("X 3 Y 4 ? 5\n", 1, "syntax", "unexpected '?'"),
    ("D 41\n", 1, "value-out-of-range", "D41 is out of range"),
    ("R1 = 41\nD R1\n", 2, "value-out-of-range", "D=41 is out of range"),
    ("X300000\n", 1, "value-out-of-range", "out of range -214000 to 214000"),
    ("R1 = 1E5\n", 1, "syntax", "unknown address E"),  # 1 ends the value; E5 is a word
    ("TRESDEL[1] X1\n", 1, "syntax", "stands alone in its block"),
]


@pytest.mark.parametrize(("text", "line", "code", "message"), SYNTAX)
def test_syntax_errors_give_file_line_and_message(text, line, code, message):
    err = error(text)
    assert (err.file, err.line, err.code) == ("p.din", line, code), str(err)
    assert message in err.message
    assert str(err).startswith(f"p.din:{line}: ") and str(err).endswith(f"[{code}]")


@pytest.mark.parametrize(("text", "hint"), [
    ("#1 = 5\n", "DIN parameters are R<n>"), ("O1234\n", "starts with %<number>"),
    ("IF [#1 GT 2] GOTO 10\n", "no GOTO"), ("G2 X10 Y0 R5 F100\n", "an arc radius R?"),
    ("G1 X10 ; move\n", "DIN comments are ( … )"),
])  # fmt: skip
def test_fanuc_style_lines_get_a_hint(text, hint):
    assert hint in error(text).message


# ---------------------------------------------------------------------- control blocks
STRUCTURE = [
    ("$ENDIF\n", 1, "$ENDIF without $IF"),
    ("R1 = 1\n$IF R1\n$ELSE\n$ELSE\n$ENDIF\n", 4, "$ELSE after $ELSE"),
    ("$IF 1\n$ELSE\n$ELSEIF 1\n$ENDIF\n", 3, "$ELSEIF after $ELSE"),
    ("$CASE 1\n", 1, "$CASE outside $SWITCH"),
    ("$BREAK\n", 1, "$BREAK outside a loop or $SWITCH"),
    ("$SWITCH 1\n$CASE 1\n$CONTINUE\n$ENDSWITCH\n", 3, "$CONTINUE outside a loop"),
    ("$WHILE 1\n$ENDFOR\n", 2, "$ENDFOR closes $FOR, but the open structure is $WHILE"),
    ("G1 F100\n$FOR R1 = 1, 2, 1\nX1\n", 2, "$FOR is not closed by $ENDFOR"),
    ("$SWITCH 1\nG0 X1\n$CASE 1\n$ENDSWITCH\n", 2, "between $SWITCH and its first $CASE"),
    ("$IF 1\n$ELSE\n$ENDWHILE\n", 3, "$ENDWHILE closes $WHILE, but the open structure is $IF"),
]


@pytest.mark.parametrize(("text", "line", "message"), STRUCTURE)
def test_unbalanced_control_blocks_are_errors_at_read_time(text, line, message):
    err = error(text)
    assert (err.file, err.line, err.code) == ("p.din", line, "control-structure") and message in err.message


def test_elsif_spelling_and_nested_structures():
    text = ("G0\n$FOR R1 = 1, 3, 1\n$FOR R2 = 1, 2, 1\n$IF R1 == 2\n$ELSIF R2 == 2\nX[R1*10+R2]\n$ENDIF\n"
            "$ENDFOR\n$ENDFOR\nM30\n")
    assert ends(text) == [(12, 0, 0), (32, 0, 0)]


def test_switch_falls_through_without_break():
    # C semantics: without $BREAK the next case's blocks run too.
    text = "$SWITCH 1\n$CASE 1\nG0 X1\n$CASE 2\nG0 Y2\n$DEFAULT\nG0 Z3\n$ENDSWITCH\nM30\n"
    assert ends(text) == [(1, 0, 0), (1, 2, 0), (1, 2, 3)]
    assert ends(text.replace("$SWITCH 1", "$SWITCH 9")) == [(0, 0, 3)]


def test_switch_compares_within_the_tolerance():
    assert ends("$SWITCH 0.3 * 3\n$CASE 0.9\nG0 X1\n$ENDSWITCH\nM30\n") == [(1, 0, 0)]
    assert ends("$SWITCH 0.9\n$CASE 0.901\nG0 X1\n$ENDSWITCH\nM30\n") == []


def test_continue_in_while_and_do_goes_to_the_test():
    text = ("R1 = 0\nG1 F100\n$WHILE R1 < 4\nR1 = R1 + 1\n$IF R1 == 2\n$CONTINUE\n$ENDIF\nX R1\n"
            "$ENDWHILE\nM30\n")
    assert ends(text) == [(1, 0, 0), (3, 0, 0), (4, 0, 0)]
    text = "R1 = 0\nG1 F100\n$DO\nR1 = R1 + 1\n$IF R1 == 2\n$CONTINUE\n$ENDIF\nX R1\n$ENDDO R1 < 3\nM30\n"
    assert ends(text) == [(1, 0, 0), (3, 0, 0)]


def test_for_counts_down_and_checks_its_step():
    assert ends("G0\n$FOR R1 = 3, 1, -1\nX R1\n$ENDFOR\nM30\n") == [(3, 0, 0), (2, 0, 0), (1, 0, 0)]
    assert ends("G0\n$FOR R1 = 3, 1, 1\nX R1\n$ENDFOR\nM30\n") == []  # never entered
    err = error("$FOR R1 = 1, 3, 0\n$ENDFOR\n")
    assert err.code == "control-structure" and err.line == 1 and "step 0" in err.message


def test_endless_loops_end_with_the_block_bound():
    err = error("$WHILE 1\n$ENDWHILE\n", max_blocks=10_000)
    assert err.code == "too-many-blocks" and err.file == "p.din" and err.line in (1, 2)
    err = error("$DO\nR1 = R1 + 1\n$ENDDO 1\n", max_blocks=5_000)
    assert err.code == "too-many-blocks"


def test_time_must_not_be_negative():
    err = error("R1 = -1\n$TIME R1\n")
    assert (err.code, err.line) == ("bad-dwell", 2)


# ---------------------------------------------------------------------- calls
def test_nesting_is_limited_to_ten_levels(tmp_path):
    # A chain of global subroutines 1 → 2 → … ; ten levels below the main program are allowed.
    for n in range(1, 13):
        (tmp_path / str(n)).write_text(f"%{n}\nG1 X{n} F100\nL{n + 1}\nM29\n" if n < 12 else "%12\nM29\n")
    main = tmp_path / "main.din"
    main.write_text("L1\nM30\n")
    err = error(main.read_text(), file=str(main))
    assert err.code == "nesting" and err.file == str(tmp_path / "10") and err.line == 3
    (tmp_path / "10").write_text("%10\nG1 X10 F100\nM29\n")
    assert len(run(main.read_text(), file=str(main))) == 10


def test_recursion_ends_with_the_nesting_error():
    err = error("%L1\nLL1\nM29\n%1\nLL1\nM30\n")
    assert err.code == "bad-call"  # a local subroutine may not call one (§7.1)
    assert "main program of their file" in err.message and err.line == 2


def test_call_errors(tmp_path):
    assert error("LL5\n").code == "program-not-found"
    assert error("L77\n").code == "program-not-found"
    (tmp_path / "5.nc").write_text("%5\nG1 X1 F100\n")
    main = tmp_path / "main.din"
    main.write_text("L5\nM30\n")
    err = error(main.read_text(), file=str(main))
    assert err.code == "bad-subroutine-end" and err.file == str(tmp_path / "5.nc") and err.line == 2
    assert error("G1 X1 F100\nM29\n").code == "bad-subroutine-end"


def test_m30_in_a_subroutine_ends_the_program_and_words_run_before_the_call(tmp_path):
    text = "%L1\nG1 X1 F100\nM30\n%1\nG0 Y5 LL1\nG0 Z9\nM30\n"
    assert ends(text) == [(0, 5, 0), (1, 5, 0)]
    (tmp_path / "7").write_text("%7\nG1 X R1 F100\nM29\n")
    main = tmp_path / "m.din"
    main.write_text("R1 = 3\nL7\nR1 = 4\nL7\nM30\n")  # data passes through the global R parameters
    assert ends(main.read_text(), file=str(main)) == [(3, 0, 0), (4, 0, 0)]
