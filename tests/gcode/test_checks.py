"""Per-block checks: modal groups, unknown and not-yet-implemented codes, unused words, error format.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import pytest
from gcode_helpers import moves, program_error

from cnc_gym.errors import CncGymError, ConfigError, ProgramError
from cnc_gym.gcode import get_dialect, interpret
from cnc_gym.gcode.dialect import DIALECT_MODULES


@pytest.mark.parametrize(
    "text",
    [
        "G00 G01 X100. Y200.\n",  # X4 (§1.3.2): the manual runs this as G01; our issue makes it an error
        "G17 G18\n",
        "G90 G91 X1\n",
        "G20 G21\n",
        "G54 G55\n",
        "G61 G64\n",
        "G04 G92 X1\n",  # two one-shot codes (group 00)
        "G01 G01 X1 F1\n",
        "M03 M04\n",
        "M08 M09\n",
        "M00 M30\n",
    ],
)
def test_two_codes_of_one_group_are_an_error(text):
    err = program_error(text)
    assert err.code == "group-conflict"


def test_codes_of_different_groups_share_a_block():
    block = "G17 G90 G21 G94 G54 G64 G40 G49 G80 G98 G50 G67 G69 G15 G97 G23 G01 X1 F100 M03 S100 T1 M08\n"
    out = moves(block)
    assert out[0]["kind"] == "line"


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("G43.4 H1\n", "G43.4"), ("G68.2\n", "G68.2"),
        ("G07.1\n", "G07.1"),
        ("G22\n", "G22"), ("G33 Z-1\n", "G33"), ("G95\n", "G95"),
        ("G107\n", "G107"), ("G53.1\n", "G53.1"),
    ],
)  # fmt: skip
def test_not_yet_implemented_codes_are_rejected_by_name(text, named):
    err = program_error(text)
    assert err.code == "not-implemented" and named in err.message


@pytest.mark.parametrize(("text", "named", "alarm"),
                         [("G12 X1\n", "G12", 10), ("G08 X1\n", "G08", 10), ("G04.5\n", "G04.5", 10),
                          ("M77\n", "M77", 201), ("G1000\n", None, 10)])  # fmt: skip
def test_unknown_codes(text, named, alarm):
    err = program_error(text)
    assert err.alarm == alarm
    if named:
        assert err.code == "unknown-code" and named in err.message
    else:
        assert err.code == "value-out-of-range"


@pytest.mark.parametrize(
    ("text", "code"),
    [
        ("G01 X1 Q5 F100\n", "unused-word"),
        ("G00 X1 P5\n", "unused-word"),
        ("G00 X1 L5\n", "unused-word"),
        ("G00 X1 A5\n", "unsupported-axis"),
        ("G00 X1 B5\n", "unsupported-axis"),
        ("M03 M08 M09 M05\n", "too-many-m-codes"),
        ("G00 " + "X1 " * 33 + "\n", "too-many-words"),  # 34 words; the limit is 32 (alarm 12)
        ("G00 X[1] " + "X1 " * 32 + "\n", "too-many-words"),
    ],
)
def test_words_without_a_meaning_are_rejected(text, code):
    err = program_error(text)
    assert err.code == code
    assert err.alarm == {"unsupported-axis": 15, "too-many-words": 12, "too-many-m-codes": 201}.get(code)


def test_error_string_is_file_line_message_code():
    err = program_error("G00 X1\n\nG01 X2\n", file="parts/a.nc")
    assert isinstance(err, ProgramError) and isinstance(err, CncGymError)
    assert (err.file, err.line, err.code, err.alarm) == ("parts/a.nc", 3, "missing-feed", 11)
    assert str(err) == f"parts/a.nc:3: {err.message} (controller alarm 11) [missing-feed]"
    assert "\n" not in str(err)


def test_program_end_stops_interpretation_and_m00_stops_the_motion():
    out = interpret("G01 X1 F100\nM00\nX2\nM30\nG01 X99\nG12\n").to_records()
    assert [r["kind"] for r in out] == ["line", "dwell", "line"]
    assert out[1] == {"kind": "dwell", "line": 2, "seconds": 0.0, "modes": ["exact_stop"]}
    # M02 ends too; M01 (optional stop switch off) does not stop; motion in an M30 block runs first.
    assert len(moves("G00 X1\nM02\nX2\n")) == 1
    assert len(moves("G00 X1\nM01\nX2\n")) == 2
    assert moves("G00 X1 M30\n")[0]["end"] == [1.0, 0.0, 0.0]


def test_a_program_without_m30_is_accepted():
    # GSK raises alarm 101 at the end of a program without M02/M30/M99; here the end of the text ends the
    # program (docs/gcode.md), which keeps snippets usable.
    assert len(moves("G00 X1\n")) == 1


def test_dialects_not_built_yet_and_unknown_dialects():
    for name in [name for name, module in DIALECT_MODULES.items() if module is None]:
        with pytest.raises(ConfigError, match="is not built"):
            interpret("G00 X1\n", dialect=name)
    with pytest.raises(ConfigError, match="unknown dialect"):
        interpret("G00 X1\n", dialect="fanuc99")
    assert get_dialect("GSK25I") is get_dialect("gsk25i")


def test_bad_block_skip_switch_is_a_config_error():
    with pytest.raises(ConfigError):
        interpret("G00 X1\n", block_skip=frozenset({10}))


def test_empty_program_gives_an_empty_toolpath():
    assert len(interpret("")) == 0
    assert len(interpret("%\n(nothing)\n%\n")) == 0
