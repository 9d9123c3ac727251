"""Errors that help: a syntax error on a line that looks like another G-code language gets a hint saying
what it probably is and how this language writes it (lang/fanuc/hints.py); ``%123`` names its file."""

from __future__ import annotations

import pytest
from gcode_helpers import program_error

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret_file


@pytest.mark.parametrize(("line", "hint"), [
    ("G01 X10 F100 ; move to the start", "a ';' comment?"),
    ("; MACHINE WARM-UP", "a ';' comment?"),
    ("o100 sub", "a LinuxCNC O-word? this dialect calls subprograms with M98"),
    ("O200 call [1] [2]", "a LinuxCNC O-word?"),
    ("o101 if [#1 GT 0]", "a LinuxCNC O-word?"),
    ("G01 Z#<depth> F100", "a LinuxCNC named parameter?"),
    ("WH[#1 LT 5]DO1", "an abbreviated macro keyword? write WHILE"),
    ("%1234", "a program number after '%'?"),
])  # fmt: skip
@pytest.mark.parametrize("dialect", ["gsk25i", "fanuc"])
def test_other_languages_syntax_gets_a_hint(line, hint, dialect):
    if dialect == "fanuc" and line.startswith("WH["):
        pytest.skip("the fanuc dialect reads Fanuc's abbreviated macro words (test_fanuc.py)")
    err = program_error(f"G00 X1.\n{line}\n", dialect=dialect)
    assert err.line == 2 and hint in err.message
    assert str(err).count("\n") == 0  # still one line


@pytest.mark.parametrize("line", [
    "G01 X10 ; G01 Y20",  # ';' is this language's end of block: no error, no hint
    "G01 X10 (MOVE TO START)",
])  # fmt: skip
def test_valid_lines_are_untouched(line):
    from gcode_helpers import moves

    assert moves(f"F100\n{line}\n")


def test_a_plain_mistake_gets_no_hint():
    err = program_error("G01 X1.2.3\n")
    assert "?" not in err.message  # a malformed number is not another language


def test_a_percent_line_names_the_file(tmp_path):
    path = tmp_path / "part.nc"
    path.write_text("%123\nG00 X1\n%\n")
    with pytest.raises(ProgramError) as info:
        interpret_file(path)
    assert str(info.value).startswith(f"{path}:1: '%' must stand alone on its line")
    assert info.value.file == str(path) and info.value.code == "bad-character"
