"""G28/G30 in tool length offset mode (§3.5.1 and §3.3).

"G28 and G30 are canceled after moving into the intermediate point … the mode code doesn't switch into
G49 … the tool length offset vector canceled by G53, G28 or G30 restores in the next block." We restore the
vector with the next block that commands the offset axis (Fanuc's reading; for a next block that moves the
axis it is the manual's "next block"), and that block's move carries it, in G90 and G91 alike.

Every case below: H1 = 20 mm, type B in G17 (vector on Z), work offsets zero, reference positions at the
machine origin.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import pytest
from gcode_helpers import program_error

from cnc_gym.gcode import interpret

H = {"H": {1: 20.0}}


def _ends(text: str) -> list[tuple[float, float, float]]:
    tp = interpret(text, tool_offsets=H)
    return [tuple(round(float(v), 6) for v in end) for end in tp.end]


@pytest.mark.parametrize("code", ["G28", "G30"])
def test_vector_is_cancelled_at_the_intermediate_point_and_restored_by_the_next_z_move(code):
    ends = _ends(f"G43 Z50 H1\n{code} Z60\nG91 X10\nZ-10\n")
    # G43 Z50 → machine 50 + 20. The intermediate point Z60 is reached with the vector (machine 80), then
    # the reference (machine 0) without it. X10 does not command Z: no restore. G91 Z-10 restores the
    # vector with its move: 0 + 20 - 10 = 10 (without the cancel it would be 0 - 10 = -10).
    assert ends == [(0, 0, 70), (0, 0, 80), (0, 0, 0), (10, 0, 0), (10, 0, 10)]


def test_absolute_move_after_g28_goes_to_program_plus_vector():
    assert _ends("G43 Z50 H1\nG28 Z60\nZ30\n")[-1] == (0, 0, 50)  # 30 + 20


def test_work_position_at_the_reference_reads_without_the_vector():
    # #5003 (block end in work coordinates without tool offsets) at the reference point: machine 0 minus the
    # work origin, the vector being cancelled: 0 (it read -20 before the cancel was modelled).
    ends = _ends("G43 Z50 H1\nG28 Z60\n#100=#5003\nG91 Z[#100+5]\n")
    assert ends[-1] == (0, 0, 25)  # 0 + 20 (restored) + 5


def test_g49_or_a_new_h_after_g28_wins_over_the_restore():
    assert _ends("G43 Z50 H1\nG28 Z60\nG49\nG91 Z-10\n")[-1] == (0, 0, -10)
    tp = interpret("G43 Z50 H1\nG28 Z60\nH2\nG90 Z0\n", tool_offsets={"H": {1: 20.0, 2: 5.0}})
    assert tuple(tp.end[-1]) == (0, 0, 5)


def test_g28_without_the_offset_axis_keeps_the_vector():
    # Only the vector of an axis G28 moves is cancelled (the other axes' are not, §3.5.1).
    assert _ends("G43 Z50 H1\nG28 X0\nG91 Z-10\n")[-1] == (0, 0, 60)


def test_g28_is_still_refused_in_canned_cycle_mode():
    assert program_error("G43 Z50 H1\nG81 X0 Y0 Z-5 R2 F100\nG28 Z60\n").alarm == 44
