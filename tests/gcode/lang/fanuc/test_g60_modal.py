"""G60 single-direction positioning as a modal group-01 code (GSK 1870#0 MDL = 1; §3.2.7).

The standard setting (MDL = 0) keeps G60 one-shot (test_coordinates.py, X14). With MDL = 1 G60 stays in
force, like G00, until another group-01 code. P1880 = (-8, 5, 0) mm as in X14: each move rapids to the end
less the overrun, dwells 1 s (§3.2.7) and rapids to the end (axes that do not move get no overrun).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from gcode_helpers import program_error

from cnc_gym.gcode import interpret
from cnc_gym.gcode.dialect import get_dialect

MDL = replace(get_dialect("gsk25i"), g60_modal=True)
P1880 = "G10 L50\nN1880 P1 R-80000\nN1880 P2 R50000\nG11\n"
TEXT = P1880 + "G90 G00 X-10 Y10\nG60 X20 Y25\nX40 Y30\nG01 X0 F100\nX-5\n"


def _moves(text: str, dialect) -> list[tuple[str, list[float]]]:
    return [(r["kind"], r.get("end")) for r in interpret(text, dialect=dialect).to_records()]


def test_the_standard_setting_is_one_shot():
    assert get_dialect("gsk25i").g60_modal is False
    assert get_dialect("gsk25i").gcodes[600].group == 0
    moves = _moves(TEXT, "gsk25i")
    # G60 X20 Y25 overshoots to (28, 20); the next block X40 Y30 is a plain G00 (one rapid).
    assert moves[4] == ("rapid", [40.0, 30.0, 0.0]) and moves[3] == ("rapid", [20.0, 25.0, 0.0])
    assert [k for k, _ in moves].count("dwell") == 1


def test_mdl_1_makes_g60_modal_until_a_group_01_code():
    assert MDL.gcodes[600].group == 1
    moves = _moves(TEXT, MDL)
    # X40 Y30 from (20, 25) in G60 mode: both axes move: (40 + 8, 30 - 5) = (48, 25), dwell, (40, 30).
    assert moves[4:7] == [("rapid", [48.0, 25.0, 0.0]), ("dwell", None), ("rapid", [40.0, 30.0, 0.0])]
    # G01 ends G60 mode: X0 and X-5 are plain feed moves.
    assert moves[7:] == [("line", [0.0, 30.0, 0.0]), ("line", [-5.0, 30.0, 0.0])]


def test_modal_g60_in_a_block_with_other_words_and_in_the_modal_table():
    # An axis block with an M code goes through the general path: still G60 positioning. #4001 reads 60.
    text = P1880 + "G60 X20 Y25\nX30 Y35 M08\n#100=#4001\nG01 X#100 F100\n"
    tp = interpret(text, dialect=MDL)
    ends = [list(map(float, e)) for e in tp.end]
    assert [38.0, 30.0, 0.0] in ends and [30.0, 35.0, 0.0] in ends  # (30 + 8, 35 - 5), then the end
    assert ends[-1] == [60.0, 35.0, 0.0]  # G01 X60: #4001 was 60 in G60 mode


def test_mdl_1_g60_and_g01_in_one_block_are_a_group_conflict():
    assert program_error("G60 G01 X5 F100\n", dialect=MDL).code == "group-conflict"
    # One-shot G60 with G01: both want the axis words.
    assert program_error("G60 G01 X5 F100\n").code == "axis-word-conflict"


@pytest.mark.parametrize("dialect", ["gsk25i", MDL])
def test_g60_without_overrun_is_a_plain_rapid(dialect):
    assert _moves("G60 X5\nX7\n", dialect) == [("rapid", [5.0, 0.0, 0.0]), ("rapid", [7.0, 0.0, 0.0])]
