"""A run leaves no reference cycle behind: its blocks are freed when ``interpret`` returns, not by a later
garbage-collector pass over every one of them (a third of a second after a 100 000-line program, paid
wherever the collector happens to run next)."""

from __future__ import annotations

import gc

import pytest

from cnc_gym.gcode import interpret

PROGRAMS = {
    "gsk25i": "G90 G21 G17\nG41 D1 G01 X10 Y0 F500\nG02 X30 Y0 R10\nG40 G01 X0 Y0\n#1=0\nWHILE[#1LT3]DO1\n"
              "#1=#1+1\nG01 X#1\nEND1\nG81 X1 Y1 Z-2 R1 F100\nX2\nG80\n" + "G01 X1 Y2\nG01 X3 Y4\n" * 200,
    "azmc1": "%1\nG01 F100\nR1=3\n$WHILE R1 > 0.5\nR1 = R1 - 1 X R1\n$ENDWHILE\n"
             + "N10 G01 X1 Y2\nX3 Y4\n" * 200,
}  # fmt: skip


@pytest.mark.parametrize("dialect", PROGRAMS)
def test_a_run_frees_its_blocks_without_the_collector(dialect):
    interpret("G01 X1 F100\n", dialect=dialect)  # first-use tables out of the count
    enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        offsets = {"D": {1: 2.0}} if dialect == "gsk25i" else None
        toolpath = interpret(PROGRAMS[dialect], dialect=dialect, tool_offsets=offsets)
        unreachable = gc.collect()
    finally:
        if enabled:
            gc.enable()
    assert len(toolpath) > 400
    assert unreachable < 50  # 400 blocks in a cycle would leave thousands of objects
