"""The toy dialect (toy_dialect.py): a variant built from tables alone behaves as its tables say.

A square corner at (10, 0) between G01 X10 and G01 Y10, chamfered by 2 along each block: the first block
ends at (8, 0), the chamfer runs to (10, 2), the second block continues to (10, 10) (worked by hand).
"""

from __future__ import annotations

from gcode_helpers import moves, program_error
from toy_dialect import TOY

PROGRAM = "G01 X10 ,{word}2 F100\nY10\n"


def test_the_toy_dialect_chamfers_with_c():
    ends = [m["end"][:2] for m in moves(PROGRAM.format(word="C"), dialect=TOY)]
    assert ends == [[8.0, 0.0], [10.0, 2.0], [10.0, 10.0]]


def test_the_toy_dialect_refuses_the_gsk_chamfer_word_and_the_gsk_refuses_its():
    assert program_error(PROGRAM.format(word="L"), dialect=TOY).code == "bad-character"
    assert program_error(PROGRAM.format(word="C")).code == "bad-character"
    gsk = [m["end"][:2] for m in moves(PROGRAM.format(word="L"))]
    assert gsk == [[8.0, 0.0], [10.0, 2.0], [10.0, 10.0]]
