"""Tool length offset G43/G44/G49 and tool position offset G45-G48 (§3.5.1, §3.5.7).

The machine starts at the machine origin with every work offset zero, so expected machine coordinates
are the programmed ones plus (G43) or minus (G44) the H value, worked out by hand per test.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from gcode_helpers import close, moves, program_error

from cnc_gym.gcode import get_dialect


def ends(text: str, **kw) -> list[list[float]]:
    return [r["end"] for r in moves(text, **kw)]


H = "G10 L10 P1 R20\nG10 L10 P2 R30\nG10 L10 P3 R11\n"  # H01 = 20, H02 = 30, H03 = 11


# ----------------------------------------------------------------------------------------------- G43/G44/G49
def test_worked_example_x55_h_replaces_not_adds():
    # §3.5.2: H01 = 20, H02 = 30. G90 G43 Z100 H01 reaches Z120; G90 G43 Z100 H02 reaches Z130
    # (the new value replaces the old one: 100 + 30, not 100 + 20 + 30).
    assert ends(H + "G90 G43 Z100.0 H01\nG90 G43 Z100.0 H02\n") == [[0, 0, 120.0], [0, 0, 130.0]]


def test_worked_example_x56_validity_sequence():
    # §3.5.1: H01; (selects only) G43 Z10 (H01 valid: 10 + 20 = 30); G44 Z20 H02 (20 - 30 = -10);
    # H03; (H03 valid, sign of G44: the next Z20 goes to 20 - 11 = 9); G49; (cancelled: Z20 is 20).
    text = H + "H01\nG43 Z10\nG44 Z20 H02\nH03\nZ20\nG49\nZ20\nM30\n"
    assert ends(text) == [[0, 0, 30.0], [0, 0, -10.0], [0, 0, 9.0], [0, 0, 20.0]]


def test_g43_g91_z0_applies_the_offset_as_a_move():
    # §3.5.1: "G43 G91 Z0 H_" applies the offset as a move: Z goes to 0 + 20. A later incremental Z-10
    # moves 10 down from there (the vector is not added twice).
    assert ends(H + "G91 G43 Z0 H1\nG01 Z-10 F100\n") == [[0, 0, 20.0], [0, 0, 10.0]]
    # An H change in a G91 block with the axis: the move carries the difference (30 - 20 = +10).
    assert ends(H + "G43 Z0 H1\nG91 Z0 H2\nX5\n") == [[0, 0, 20.0], [0, 0, 30.0], [5, 0, 30.0]]


def test_h00_and_g49_cancel():
    # §3.5.1: G49 or H00 cancels at once; the next move of the axis goes to the programmed position.
    assert ends(H + "G43 Z0 H1\nG91 H0 Z0\n") == [[0, 0, 20.0], [0, 0, 0.0]]
    assert ends(H + "G43 Z0 H1\nG49 Z0\n") == [[0, 0, 20.0], [0, 0, 0.0]]


def test_uncommanded_axes_keep_their_position_when_h_changes():
    # The vector is part of the origin (like a work offset): an X-only move after H03 does not move Z; the
    # next absolute Z move applies it.
    assert ends(H + "G43 Z0 H1\nH3\nX5\nZ0\n") == [[0, 0, 20.0], [5, 0, 20.0], [5, 0, 11.0]]


def test_type_b_offsets_the_axis_normal_to_the_plane_and_type_a_always_z():
    # 2600#1 TLB = 1 (type B, GSK standard): G18 G43 Y_ offsets Y, G19 G43 X_ offsets X.
    assert ends(H + "G18 G43 Y10 H1\n") == [[0, 30.0, 0]]
    assert ends(H + "G19 G43 X10 H1\n") == [[30.0, 0, 0]]
    assert ends(H + "G17 G43 Z10 H1\n") == [[0, 0, 30.0]]
    # Type A: always Z.
    gsk = get_dialect("gsk25i")
    type_a = replace(gsk, compensation=replace(gsk.compensation, tool_length_type="A"))
    assert ends(H + "G18 G43 Y10 Z0 H1\n", dialect=type_a) == [[0, 10.0, 20.0]]


def test_work_offsets_and_length_offset_add():
    # machine = program + work offset + length vector: G54 Z = -100, H01 = 20: G43 Z5 → -100 + 5 + 20.
    assert ends(H + "G10 L2 P1 Z-100\nG54 G43 Z5 H1\n") == [[0, 0, -75.0]]


def test_g53_cancels_the_vector_for_its_move_and_it_is_restored_next():
    # §3.5.1: G53 reaches its machine position without the vector; the next block restores it.
    assert ends(H + "G43 Z10 H1\nG53 Z0\nZ10\n") == [[0, 0, 30.0], [0, 0, 0.0], [0, 0, 30.0]]


def test_canned_cycle_example_x46_first_tool():
    # X46 (§3.4.15): G92 X0 Y0 Z0 at the reference; G00 Z250 T11 M6; G43 Z0 H11 with H11 = 200: the
    # tool tip goes to Z0 in program coordinates = machine Z 200 (Z250 first, then down 50).
    text = "G10 L10 P11 R200\nN001 G92 X0 Y0 Z0\nN002 G90 G00 Z250 T11 M6\nN003 G43 Z0 H11\nN012 G49 Z250\n"
    assert ends(text) == [[0, 0, 250.0], [0, 0, 200.0], [0, 0, 250.0]]


def test_tool_offsets_argument_and_macro_variables_share_the_table():
    # interpret(tool_offsets=...) preloads H; #11001 (H geometry 1) and #10001 (H wear 1) write the same
    # memory the G43 block reads: geometry + wear.
    assert ends("G43 Z0 H1\n", tool_offsets={"H": {1: 12.5}}) == [[0, 0, 12.5]]
    assert ends("#11001=7\n#10001=0.5\nG43 Z0 H1\n") == [[0, 0, 7.5]]


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("G43 H1\n", "length-no-axis", 27),  # T8: NO AXES COMMANDED IN G43/G44
        ("G44 H1\n", "length-no-axis", 27),
        ("G43 G03 X0 Y0 Z5 I5 H1 F100\n", "length-helical", None),  # T11: not in a helical block (§3.2.3)
        ("G01 Z1 H257 F100\n", "value-out-of-range", 30),
        ("G10 L10 P1 R1000\n", "bad-offset-value", 32),
        ("G10 L11 P1 R-100\n", "bad-offset-value", 32),
        ("G10 L10 P300 R1\n", "bad-offset-number", 30),
        ("G10 L10 R1\n", "bad-g10", 31),
        ("G10 L10 P1\n", "missing-value", 5),
        ("G01 Z1 H1.5 F100\n", "decimal-point-not-allowed", 7),
    ],
)  # fmt: skip
def test_tool_length_alarms(text, code, alarm):
    err = program_error(text)
    assert (err.code, err.alarm) == (code, alarm), str(err)


# ----------------------------------------------------------------------------------------------- G45-G48
def test_worked_example_x62_tool_position_offset():
    # §3.5.7 with D01 = 10, all G91. Each commanded axis's travel grows (G45 +1x, G47 +2x) or shrinks
    # (G46 -1x, G48 -2x) by the offset along its own direction; N3/N5 have no code (uncompensated).
    #   N1 G46 G00 X80 Y50     → X 70, Y 40          → (70, 40)
    #   N2 G47 G01 X50          → X 50 + 20           → (140, 40)
    #   N3 Y40                  →                     → (140, 80)
    #   N4 G48 X40              → X 40 - 20           → (160, 80)
    #   N5 Y-40                 →                     → (160, 40)
    #   N6 G45 X30              → X 40                → (200, 40)
    #   N7 G45 G03 X30 Y30 J30  → a quarter circle: radius 30 + 10, centre J40 → (240, 80) about (200, 80)
    #   N8 G45 G01 Y20          → Y 30                → (240, 110)
    #   N9 G46 X0               → zero move in G91: -X by the offset (the manual's note) → (230, 110)
    #   N10 G46 G02 X-30 Y30 J30→ radius 30 - 10: (-20, 20), centre J20 → (210, 130) about (230, 130)
    #   N11 G45 G01 Y0          → zero move: +Y by the offset → (210, 140)
    #   N12 G47 X-120           → X -140              → (70, 140)
    #   N13 G47 Y-80            → Y -100              → (70, 40)
    #   N14 G46 G00 X-80 Y-50   → X -70, Y -40        → (0, 0)
    # N14 is printed "X80.0": the X travel of the printed program sums to 160, not 0, while every other
    # block makes a closed figure; with X-80 (the Fanuc original) the tool returns to the start. We test the
    # corrected reading.
    text = ("G10 L12 P1 R10\nN1 G91 G46 G00 X80.0 Y50.0 D01\nN2 G47 G01 X50.0 F120.0\nN3 Y40.0\n"
            "N4 G48 X40.0\nN5 Y-40.0\nN6 G45 X30.0\nN7 G45 G03 X30.0 Y30.0 J30.0\nN8 G45 G01 Y20.0\n"
            "N9 G46 X0\n"
            "N10 G46 G02 X-30.0 Y30.0 J30.0\nN11 G45 G01 Y0\nN12 G47 X-120.0\nN13 G47 Y-80.0\n"
            "N14 G46 G00 X-80.0 Y-50.0\n")  # fmt: skip
    out = moves(text)
    assert [r["end"][:2] for r in out] == [
        [70, 40], [140, 40], [140, 80], [160, 80], [160, 40], [200, 40], [240, 80], [240, 110], [230, 110],
        [210, 130], [210, 140], [70, 140], [70, 40], [0, 0],
    ]  # fmt: skip
    assert out[6]["kind"] == "arc" and close(out[6]["center"][:2], (200, 80)) and out[6]["radius"] == 40.0
    assert out[9]["kind"] == "arc" and close(out[9]["center"][:2], (230, 130)) and out[9]["radius"] == 20.0
    assert [r["kind"] for r in out][:2] == ["rapid", "line"]


def test_position_offset_in_g90_and_direction_reversal():
    # §3.5.7: in G90 the travel from the previous end point grows; a zero travel does not move. §3.5.7: a
    # decrease larger than the travel reverses it: G91 G46 X5 with D = 10 moves -5.
    # G00 X10; G45 X30: travel 20 grows to 30 → X40; G45 X40: zero travel, no move; G45 X30: travel -10
    # grows to -20 → X20.
    assert ends("G10 L12 P1 R10\nG00 X10\nG90 G45 X30 D1\nG45 X40\nG45 X30\n") == [
        [10, 0, 0],
        [40, 0, 0],
        [20, 0, 0],
    ]
    assert ends("G10 L12 P1 R10\nG91 G46 X5 D1\n") == [[-5, 0, 0]]
    # Negative D: G45 with D = -10 decreases.
    assert ends("G10 L12 P1 R-10\nG91 G45 X30 D1\n") == [[20, 0, 0]]
    # One-shot: the next block without the code is plain.
    assert ends("G10 L12 P1 R10\nG91 G45 X30 D1\nX30\n") == [[40, 0, 0], [70, 0, 0]]


def test_position_offset_on_other_arcs_is_an_error():
    # §3.5.7: only quarter and three-quarter circles with I/J/K.
    err = program_error("G10 L12 P1 R10\nG91 G45 G03 X10 Y0 I5 D1 F100\n")
    assert err.code == "position-offset-arc"


def test_g91_in_the_same_block_counts_for_the_zero_move_rule():
    # G90/G91 run after the compensation steps in the order of execution; the zero-move rule still sees
    # the block's own G91: G91 G45 X0 moves +D, G90 G45 X0 (at X0) does not move.
    assert ends("G10 L12 P1 R10\nG91 G45 X0 D1\n") == [[10, 0, 0]]
    assert ends("G10 L12 P1 R10\nG91\nG90 G45 X0 D1\nG00 X1\n") == [[1, 0, 0]]
