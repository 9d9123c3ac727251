"""Cutter radius compensation C (G40/G41/G42, G39): §3.5.2-§3.5.4.

Expected tool-centre paths are worked out by hand in each test with the small closed forms below (offset
lines as ``n·p = c``, line/line, line/circle and circle/circle intersections), written independently of
``cnc_gym.gcode.lang.fanuc.compensation``. G41 puts the tool on the left of the direction of travel, G42 on
the right;
D holds the radius (the examples' reading of §3.5.2, where the text says "diameter").

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

import pytest
from gcode_helpers import close, moves, program_error

from cnc_gym.errors import ConfigError
from cnc_gym.gcode import interpret


# --------------------------------------------------------------------------------------- hand geometry
def left_normal(p0, p1):
    dx, dy = p1[0] - p0[0], p1[1] - p0[1]
    n = math.hypot(dx, dy)
    return (-dy / n, dx / n)


def offset_line(p0, p1, d):
    """The line through p0-p1 shifted by d to the left, as (n, c) with n·p = c."""
    n = left_normal(p0, p1)
    return n, n[0] * p0[0] + n[1] * p0[1] + d


def meet(line_a, line_b):
    """Intersection of n1·p = c1 and n2·p = c2 (Cramer's rule)."""
    (a1, b1), c1 = line_a
    (a2, b2), c2 = line_b
    det = a1 * b2 - a2 * b1
    return ((c1 * b2 - c2 * b1) / det, (a1 * c2 - a2 * c1) / det)


def circles_meet(c1, r1, c2, r2, near):
    """The intersection of two circles nearest ``near``."""
    dx, dy = c2[0] - c1[0], c2[1] - c1[1]
    dist = math.hypot(dx, dy)
    a = (dist**2 + r1**2 - r2**2) / (2 * dist)
    h = math.sqrt(r1**2 - a**2)
    mx, my = c1[0] + a * dx / dist, c1[1] + a * dy / dist
    points = [(mx - h * dy / dist, my + h * dx / dist), (mx + h * dy / dist, my - h * dx / dist)]
    return min(points, key=lambda p: math.dist(p, near))


def xy(record):
    return record["end"][:2]


def ends(text, **kw):
    return [xy(r) for r in moves(text, **kw)]


def assert_path(text, expected, tol=1e-6, **kw):
    got = ends(text, **kw)
    assert len(got) == len(expected), (got, expected)
    for g, e in zip(got, expected, strict=True):
        assert close(g, e, tol), (got, expected)


R10 = "G10 L12 P7 R10\n"  # D07 = 10 mm radius


# ------------------------------------------------------------------------------------------------- X57
X57 = (
    "G92 X0 Y0 Z0\n"
    "N1 G90 G17 G00 G41 D07 X250.0 Y550.0\n"
    "N2 G01 Y900.0 F150\n"
    "N3 X450.0\n"
    "N4 G03 X500.0 Y1150.0 I-600.0 J250.0\n"
    "N5 G02 X900.0 I200.0 J150.0\n"
    "N6 G03 X950.0 Y900.0 I650.0 J0\n"
    "N7 G01 X1150.0\n"
    "N8 Y550.0\n"
    "N9 X700.0 Y650.0\n"
    "N10 X250.0 Y550.0\n"
    "N11 G00 G40 X0 Y0\n"
)


def test_worked_example_x57_contour_with_g41():
    # §3.5.2 with two repairs: N7 restored (X1150) and N6 with I650 (the printed I250 fails
    # the radius check). D07 = 10. Left offset, r = 10.
    r = 10.0
    # N1 start-up (0,0)→(250,550), then N2 goes straight up: a left turn with the tool on the left = an
    # inner corner: the start-up ends at the intersection of N1's offset line and x = 250 - r.
    p1 = meet(offset_line((0, 0), (250, 550), r), ((1.0, 0.0), 240.0))
    # N2/N3: up then right, a 90° outer corner: the offset lines x = 240 and y = 910 meet at (240, 910).
    p2 = (240.0, 910.0)
    # N3 → N4: N4 is CCW about (450-600, 900+250) = (-150, 1150), R 650; left of a CCW arc is the centre
    # side, so the offset circle has R 640. Inner corner: y = 910 meets it at x = -150 + sqrt(640²-240²).
    p3 = (-150.0 + math.sqrt(640.0**2 - 240.0**2), 910.0)
    # N4 → N5 at (500, 1150): N5 is CW about (700, 1300), R 250 (left of a CW arc is outside: 260).
    # Tangents (0, 1) then (-0.6, 0.8): a left turn, inner: the two offset circles meet.
    p4 = circles_meet((-150.0, 1150.0), 640.0, (700.0, 1300.0), 260.0, (500.0, 1150.0))
    # N5 → N6 at (900, 1150): N6 CCW about (1550, 1150), R 650 → 640; the mirror image of N4/N5 in x = 700.
    p5 = circles_meet((700.0, 1300.0), 260.0, (1550.0, 1150.0), 640.0, (900.0, 1150.0))
    assert close(p5, (1400.0 - p4[0], p4[1]))
    # N6 → N7 at (950, 900): inner again; the offset circle meets y = 910.
    p6 = (1550.0 - math.sqrt(640.0**2 - 240.0**2), 910.0)
    # N7 → N8: right then down, 90° outer: (1160, 910).
    p7 = (1160.0, 910.0)
    # N8 → N9 at (1150, 550): down, then toward (700, 650): the turn is to the right by more than 90°, an
    # acute outer corner (alpha < 90°): extension points. N8's line runs on r past its offset end to
    # (1160, 540); then to the point r before N9's offset start along N9's direction.
    t9 = ((700 - 1150) / math.hypot(450, 100), (650 - 550) / math.hypot(450, 100))
    n9 = (-t9[1], t9[0])
    q2 = (1150 + r * n9[0] - r * t9[0], 550 + r * n9[1] - r * t9[1])
    # N9 → N10 at (700, 650): a left turn (inner); by symmetry about x = 700 the offset lines meet at
    # x = 700, r / cos(angle) below 650: y = 650 - r * |(450, 100)| / 450.
    p9 = (700.0, 650.0 - r * math.hypot(450, 100) / 450)
    assert close(p9, meet(offset_line((1150, 550), (700, 650), r), offset_line((700, 650), (250, 550), r)))
    # N10 → N11 (G40 back to the origin): a left turn, inner: N10 ends at the intersection of its offset
    # line with the cancel line's offset line; the cancel line then runs to (0, 0) without offset.
    p10 = meet(offset_line((700, 650), (250, 550), r), offset_line((250, 550), (0, 0), r))
    expected = [p1, p2, p3, p4, p5, p6, p7, (1160.0, 540.0), q2, p9, p10, (0.0, 0.0)]
    out = moves(R10 + X57)
    kinds = ["rapid", "line", "line", "arc", "arc", "arc", "line", "line", "line", "line", "line", "rapid"]
    assert [r_["kind"] for r_ in out] == kinds
    assert [r_["line"] for r_ in out] == [3, 4, 5, 6, 7, 8, 9, 10, 11, 11, 12, 13]  # q2 belongs to N9
    for got, want in zip(out, expected, strict=True):
        assert close(xy(got), want, 1e-6), (xy(got), want)
    # The arcs keep their programmed centres, on the offset circles.
    assert [a["center"][:2] for a in out[3:6]] == [[-150.0, 1150.0], [700.0, 1300.0], [1550.0, 1150.0]]
    assert [round(a["radius"], 9) for a in out[3:6]] == [640.0, 260.0, 640.0]
    # Every offset-mode line lies at exactly r from its programmed line: N2 x = 240, N3 y = 910, N7 y = 910,
    # N8 x = 1160, N9 and N10 at distance r.
    for index, (p0, p1_) in ((8, ((1150, 550), (700, 650))), (9, ((1150, 550), (700, 650))),
                             (9, ((700, 650), (250, 550))), (10, ((700, 650), (250, 550)))):  # fmt: skip
        n, c = offset_line(p0, p1_, r)
        point = xy(out[index])
        assert math.isclose(n[0] * point[0] + n[1] * point[1], c, abs_tol=1e-6)


def test_worked_example_x57_as_printed_fails_the_radius_check():
    # N6 as printed (I250 J0): start radius 250, end radius 320: alarm 20 (docs/gsk25i_examples.md X57).
    bad = X57.replace("I650.0 J0", "I250.0 J0")
    assert program_error(R10 + bad).alarm == 20


def test_x57_with_g42_and_negative_d_are_the_same_path():
    # A negative offset swaps G41 and G42 (§3.5.2, §3.5.3): G42 with D = -10 is G41 with D = 10.
    assert ends("G10 L12 P7 R-10\n" + X57.replace("G41", "G42")) == ends(R10 + X57)


# --------------------------------------------------------------------------------------------- corners
SQUARE = "G01 G41 D1 X10 Y10 F100\nY50\nX50\nY10\nX10\nG40 X0 Y0\n"


def test_outer_square_corners_are_intersection_points():
    # A square traced clockwise (up, right, down, left) with G41: the tool is outside; every corner is a
    # 90° outer corner: the offset lines meet r diagonally out. r = 2.
    # Start-up (0,0)→(10,10) then up: a left turn with the tool on the left → inner corner: the intersection
    # of the start-up line's offset with x = 8: the line x - y = 2·sqrt(2)·... computed with meet().
    r = 2.0
    start = meet(offset_line((0, 0), (10, 10), r), ((1.0, 0.0), 8.0))
    # Cancel: from (10,10) toward (0,0) after travelling -x: a left turn again (inner): intersection of
    # y = 12 (left of -x travel is +y... travelling -x the left normal is (0,-1): y = 10 - 2 = 8).
    end = meet(offset_line((50, 10), (10, 10), r), offset_line((10, 10), (0, 0), r))
    expected = [start, (8.0, 52.0), (52.0, 52.0), (52.0, 8.0), end, (0.0, 0.0)]
    assert_path("G10 L12 P1 R2\n" + SQUARE, expected)


def test_inner_square_corners_with_g42_are_intersection_points():
    # The same square with G42: the tool is inside, every offset-mode corner inner: (12, 48), (48, 48),
    # (48, 12). The start-up (45° line, then up) turns left with the tool on the right: an outer obtuse
    # corner; start-up type A (the GSK default here) ends perpendicular to the next block: (10 + 2, 10).
    # The cancel (-x, then toward (0, 0)) also turns left: outer; type A: perpendicular to the last block
    # (right of -x is +y): (10, 12), then straight to (0, 0).
    assert_path("G10 L12 P1 R2\n" + SQUARE.replace("G41", "G42"),
                [(12, 10), (12, 48), (48, 48), (48, 12), (10, 12), (0, 0)])  # fmt: skip


def test_acute_outer_corner_inserts_extension_points():
    # From (0,0) along +x to (20,0), then back to (0,10) (a 153° turn to the left); G42 (tool on the
    # right) makes it an outer corner with alpha = 180 - 153 < 90: extension points.
    # r = 1. Block A's offset line y = -1 runs on r past the corner: (21, -1). Block B direction
    # t = (-20, 10)/|..|, right normal -left(t); the point r before its offset start: P + r·nR - r·t.
    r = 1.0
    t = (-20 / math.hypot(20, 10), 10 / math.hypot(20, 10))
    n_right = (t[1], -t[0])
    q2 = (20 + r * n_right[0] - r * t[0], 0 + r * n_right[1] - r * t[1])
    text = "G10 L12 P1 R1\nG00 X-10 Y-5\nG01 G42 D1 X0 Y0 F100\nX20 Y0\nX0 Y10\nX-10 Y10\nG40 X-20 Y20\n"
    out = moves(text)
    points = [xy(p) for p in out]
    assert close(points[2], (21.0, -1.0))
    assert close(points[3], q2)
    # B's compensated line continues from q2 along B's direction: q2, B's offset end are collinear with t.
    b_end = points[4]
    cross = (b_end[0] - q2[0]) * t[1] - (b_end[1] - q2[1]) * t[0]
    assert abs(cross) < 1e-7
    assert out[3]["line"] == out[4]["line"] == 5  # the extension move belongs to block B (§3.5.3)


def test_arc_to_arc_inner_corner_and_line_to_arc_tangent():
    # A line along +x into a tangent CCW half circle (tangent join: no corner), then a CW arc that turns
    # back (a reversal of curvature with a left turn = inner for G41). G41 r = 1:
    #   line y = 0 → y = 1 (left of +x).
    #   CCW half circle about (10, 5) R5 from (10, 0) to (10, 10): offset R = 4 (centre side).
    #   G02 from (10, 10) to (4, 10) about (7, 10) (R 3, CW): offset R = 3 + 1 = 4 (outside).
    # At (10, 10) the first arc's end tangent is (-1, 0), the CW arc's start tangent: radial (1,0) → (0,-1)
    # ... a left turn: inner: circles ((10,5), 4) and ((7,10), 4) meet near (10, 10).
    # The first line (0,0)→(10,0) is the start-up; its corner with the tangent arc is smooth: (10, 1).
    text = ("G10 L12 P1 R1\nG01 G41 D1 X0 Y0 F100\nX10\nG03 X10 Y10 J5\nG02 X4 Y10 I-3\n"
            "G01 X4 Y20\nG40 X0 Y30\n")  # fmt: skip
    out = moves(text)
    kinds = [r["kind"] for r in out]
    assert kinds == ["line", "arc", "arc", "line", "line"]
    assert close(xy(out[0]), (10.0, 1.0))  # smooth join: the perpendicular point, no extra move
    p = circles_meet((10.0, 5.0), 4.0, (7.0, 10.0), 4.0, (10.0, 10.0))
    assert close(xy(out[1]), p)
    assert math.isclose(out[1]["radius"], 4.0) and math.isclose(out[2]["radius"], 4.0)
    # CW arc → line up at (4, 10): the arc's end radial is (-1, 0), its CW tangent (0, 1); the line goes
    # +y: smooth; left of +y is -x: (3, 10).
    assert close(xy(out[2]), (3.0, 10.0))


def test_program_ending_in_offset_mode_keeps_the_vector_perpendicular_to_the_last_block():
    # §3.5.3: the end point is offset by one vector. Last block along +x with G41 r = 2: ends at (20, 2).
    assert ends("G10 L12 P1 R2\nG01 G41 D1 X10 F100\nX20\n")[-1] == [20.0, 2.0]


def test_d00_does_not_start_compensation():
    # Start-up needs D ≠ 00 (§3.5.3): with D00 the path is the programmed one.
    assert ends("G01 G41 D0 X10 Y10 F100\nY50\nG40 X0\n") == [[10.0, 10.0], [10.0, 50.0], [0.0, 50.0]]


def test_zero_offset_with_d_number_is_the_programmed_path():
    # The default offset memory is all zero: D1 = 0 → no vector.
    assert ends("G01 G41 D1 X10 Y10 F100\nY50\nG40 X0\n") == [[10.0, 10.0], [10.0, 50.0], [0.0, 50.0]]


def test_d00_in_offset_mode_cancels():
    # §3.5.3 (a): D00 cancels like G40. G41 r = 2 along +y, then D0 X10: the corner at (0, 20) turning right
    # is outer; start-up type A cancel: the vector perpendicular to the last block, then straight to (10, 20).
    out = ends("G10 L12 P1 R2\nG01 G41 D1 X0 Y10 F100\nY20\nD0 X10 Y20\n")
    assert close(out[-2], (-2.0, 20.0)) and close(out[-1], (10.0, 20.0))


def test_type_a_and_b_start_up_at_an_outer_corner():
    # Start-up from (0, 0) along +x to (10, 0), then up-right at 45°... a left turn; use G42 (tool on the
    # right) to make it an outer corner (obtuse, alpha = 135°). r = 1.
    # Type A (§3.5.2): the start-up ends at the vector perpendicular to the NEXT block: the next block's
    # right normal at its start: t = (1,1)/√2 → right normal (1,-1)/√2.
    # Type B: the intersection of the start-up line's offset (y = -1) and the next block's offset line.
    text = "G10 L12 P1 R1\nG01 G42 D1 X10 Y0 F100\nX20 Y10\nG40 X30 Y10\n"
    a = ends(text)[0]
    assert close(a, (10 + 1 / math.sqrt(2), -1 / math.sqrt(2)))
    from dataclasses import replace

    from cnc_gym.gcode import get_dialect

    gsk = get_dialect("gsk25i")
    type_b = replace(gsk, compensation=replace(gsk.compensation, startup_type="B"))
    b = ends(text, dialect=type_b)[0]
    assert close(b, meet(offset_line((0, 0), (10, 0), -1.0), offset_line((10, 0), (20, 10), -1.0)))


def test_type_b_acute_start_up_uses_extension_points():
    # Start-up along +x to (10, 0), then back to (0, 5) (a left turn of 153°) with G42: outer acute.
    # Type B: the start-up line runs to r past its offset end (11, -1); an extra move to r before the next
    # block's offset start.
    from dataclasses import replace

    from cnc_gym.gcode import get_dialect

    gsk = get_dialect("gsk25i")
    type_b = replace(gsk, compensation=replace(gsk.compensation, startup_type="B"))
    text = "G10 L12 P1 R1\nG01 G42 D1 X10 Y0 F100\nX0 Y5\nG40 X-5 Y5\n"
    out = ends(text, dialect=type_b)
    t = (-10 / math.hypot(10, 5), 5 / math.hypot(10, 5))
    n_right = (t[1], -t[0])
    assert close(out[0], (11.0, -1.0))
    assert close(out[1], (10 + n_right[0] - t[0], n_right[1] - t[1]))
    # Type A: straight to the vector perpendicular to the next block.
    assert close(ends(text)[0], (10 + n_right[0], n_right[1]))


def test_cancel_with_ij_direction():
    # §3.5.3: (G42) G40 X_ Y_ I_ J_: the previous block ends where its offset path meets the offset
    # line of the (I, J) direction from its end. G41 r = 1 along +x to (10, 0); G40 I0 J1: the virtual
    # direction +y; offsets y = 1 and x = 9 meet at (9, 1). Then straight to (20, 20).
    out = ends("G10 L12 P1 R1\nG01 G41 D1 X0 Y0 F100\nX10\nG40 X20 Y20 I0 J1\n")
    assert close(out[-2], (9.0, 1.0)) and close(out[-1], (20.0, 20.0))


def test_g40_without_a_move_leaves_the_vector_until_the_next_move():
    # §3.5.3: G40 in a block without movement: the vector stays perpendicular to the previous block and is
    # cancelled by the next move. G41 r = 1 along +x to (10, 0): the tool stops at (10, 1), then (10, 10).
    out = ends("G10 L12 P1 R1\nG01 G41 D1 X0 Y0 F100\nX10\nG40\nY10\n")
    assert close(out[-2], (10.0, 1.0)) and close(out[-1], (10.0, 10.0))


def test_switching_g41_to_g42_uses_the_intersection_of_both_offsets():
    # §3.5.3: the inside/outside concept is dropped; the offset paths intersect: left offset of +x
    # (y = 1) and right offset of the 45° line. r = 1.
    # (Switching is not allowed between the start-up block and the next one, §3.5.3: the start-up here is
    # the move to (0, 0).)
    text = "G10 L12 P1 R1\nG00 X-10\nG01 G41 D1 X0 Y0 F100\nX10\nG42 X20 Y10\nX30 Y10\nG40 X40 Y0\n"
    out = ends(text)
    assert close(out[2], meet(offset_line((0, 0), (10, 0), 1.0), offset_line((10, 0), (20, 10), -1.0)))


def test_changing_d_in_offset_mode_applies_from_the_end_vector_of_the_block():
    # §3.5.3: the new value applies to the end vector of the block that carries it. r1 = 1, r2 = 3,
    # +x then the D2 block up: the corner at (10, 0) still uses r1 (11 ... outer 90° corner with G42:
    # (11, -1)); the D2 block's end vector uses 3.
    text = "G10 L12 P1 R1\nG10 L12 P2 R3\nG00 X-10\nG01 G42 D1 X0 Y0 F100\nX10\nD2 Y10\nX0\nG40 X0 Y-10\n"
    out = ends(text)
    assert close(out[2], (11.0, -1.0))
    assert close(out[3], (13.0, 13.0))  # corner (10, 10), up then -x, outer 90° with r = 3


def test_changing_d_in_an_arc_block_keeps_the_old_offset_at_its_start_vector():
    # §3.5.3 for an arc: the arc block carrying D2 starts from the vector of the old offset and ends with
    # the new one. G42 r1 = 1 along +x to (10, 0), then D2 (r2 = 3) CCW quarter about (10, 10) to
    # (20, 10): G42 is the outside of a CCW arc (radius 10 + r). The join is tangent: one point, the
    # arc's start vector with r1, (10, -1). The tool then steps radially onto the r2 circle, (10, -3),
    # runs on it (radius 13) to the tangent join with the +y line: the end vector with r2, (23, 10).
    text = "G10 L12 P1 R1\nG10 L12 P2 R3\nG00 X-10\nG01 G42 D1 X0 Y0 F100\nX10\nD2 G03 X20 Y10 J10\nG01 Y20\n"
    out = moves(text)
    for got, expected in zip(out[2:6], [(10, -1), (10, -3), (23, 10), (23, 20)], strict=True):
        assert close(xy(got), expected), out
    assert out[3]["line"] == out[4]["line"] == 6 and out[3]["kind"] == "line"
    assert out[4]["kind"] == "arc" and close(out[4]["radius"], 13.0) and close(out[4]["sweep_deg"], 90.0)


# ------------------------------------------------------------------------------------------ look-ahead
def _fanuc_units():
    """The examples copied from Fanuc are printed in 0.001 mm units without decimal points (X50000 = 50 mm,
    §2.5): a dialect variant with DPI = 0 and a 0.001 mm least increment reads them as printed."""
    from dataclasses import replace

    from cnc_gym.gcode import get_dialect

    return replace(get_dialect("gsk25i"), integer_is_unit=False, least_increment_mm=0.001)


def test_x59_one_z_block_between_is_read_ahead():
    # §3.5.3, as printed (0.001 mm units): N1 start-up to (50, 50), N3 a Z move, N6 along +y. The NC
    # reads N3 and N6 with N1: the start-up corner is computed with N6 (a left turn after the 45°
    # start-up, inner for G41): the intersection of both offset lines; D1 = 5 mm.
    text = "G10 L12 P1 R5.0\nN1 G91 G00 G41 X50000 Y50000 D1\nN3 G01 Z-30000 F1\nN6 Y100000 F2\n"
    out = moves(text, dialect=_fanuc_units())
    want = meet(offset_line((0, 0), (50, 50), 5.0), ((1.0, 0.0), 45.0))
    assert close(xy(out[0]), want)
    assert close(out[1]["end"], [want[0], want[1], -30.0])  # the Z move at the compensated point


def test_x59_two_z_blocks_starve_the_look_ahead():
    # Z split into N3 and N5: N6 is not in the buffer when N1 runs, the start-up vector is perpendicular to
    # N1 itself (the overcut of §3.5.3): (50, 50) + 5·(-1, 1)/√2.
    text = "G10 L12 P1 R5.0\nN1 G91 G00 G41 X50000 Y50000 D1\nN3 Z-25000\nN5 G01 Z-5000 F1\nN6 Y100000 F2\n"
    out = moves(text, dialect=_fanuc_units())
    assert close(xy(out[0]), (50 - 5 / math.sqrt(2), 50 + 5 / math.sqrt(2)))
    # N6 then runs from that point to its own end vector (straight from the old vector tip to the new).
    assert close(xy(out[-1]), (45.0, 150.0))


def test_x59_the_n2_fix_restores_the_corner():
    # §3.5.3: N2 Y10 (same direction as N6) before the Z moves: N1's corner is computed with N2:
    # N1 (0,0)→(50,40), then +y: inner for G41: intersection with x = 45.
    text = (
        "G10 L12 P1 R5.0\nN1 G91 G00 G41 X50000 Y40000 D1\nN2 Y10000\nN3 Z-25000\nN5 G01 Z-5000 F1\n"
        "N6 Y100000 F2\n"
    )
    out = moves(text, dialect=_fanuc_units())
    assert close(xy(out[0]), meet(offset_line((0, 0), (50, 40), 5.0), ((1.0, 0.0), 45.0)))
    assert close(xy(out[1]), (45.0, 50.0))
    assert all(close(xy(r), (45.0, 50.0)) for r in out[2:4])  # the Z moves at the right vector
    assert close(xy(out[-1]), (45.0, 150.0))


def test_dwell_and_m_codes_count_as_blocks_without_motion():
    # One non-move block between two in-plane moves: the corner is still right (outer 90°, G41 going up
    # then -x... up then +x with G41 is outer: (−1, 11)... up then right turn = outer: (x=-1, y=11)).
    out = moves("G10 L12 P1 R1\nG00 Y-10\nG01 G41 D1 X0 Y0 F100\nY10\nG04 P100\nX10\nG40 X20 Y0\n")
    assert close(xy(out[2]), (-1.0, 11.0))


# ------------------------------------------------------------------------------------------------- G39
def test_g39_corner_arc_of_the_offset_radius():
    # §3.5.4: G39 at an outer corner inserts an arc of radius = offset about the corner; its end vector
    # is perpendicular to the next block's start. G41 r = 2, up to (0, 10) then +x: the first block ends
    # at (-2, 10) (perpendicular), an arc about (0, 10) to (0, 12), then along y = 12.
    out = moves("G10 L12 P1 R2\nG00 Y-10\nG01 G41 D1 X0 Y0 F100\nY10\nG39\nX10\nG40 X20 Y0\n")
    assert close(xy(out[2]), (-2.0, 10.0))
    arc = out[3]
    assert arc["kind"] == "arc" and close(arc["center"][:2], (0.0, 10.0)) and math.isclose(arc["radius"], 2.0)
    assert close(xy(arc), (0.0, 12.0)) and math.isclose(arc["sweep_deg"], -90.0)
    # The next block runs on y = 12 (left of +x); the cancel corner (+x, then down-right) turns right:
    # outer, type A: perpendicular to the last block at (10, 12), then to (20, 0).
    assert [xy(r) for r in out[4:]] == [[10.0, 12.0], [20.0, 0.0]]


def test_g39_outside_offset_mode_is_an_error():
    assert program_error("G39\n").code == "g39-without-comp"


# ---------------------------------------------------------------------------------------------- alarms
@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        # T1: arc in the start-up block (§3.5.3) and in the cancel block (§3.5.3).
        ("G10 L12 P1 R1\nG41 D1 G02 X10 Y0 R5 F100\n", "comp-arc-startup", 34),
        ("G10 L12 P1 R1\nG01 G41 D1 X10 F100\nY10\nG40 G02 X20 Y20 R10\n", "comp-arc-startup", 34),
        # T3: plane change in offset mode (§3.5.3).
        ("G10 L12 P1 R1\nG01 G41 D1 X10 F100\nG18\n", "comp-plane-change", 37),
        # T4: the tool-centre arc degenerates: radius of an inner arc = the offset (centre = start = end).
        ("G10 L12 P1 R5\nG01 G41 D1 X10 F100\nG03 X20 Y0 R5\nG01 X30\n", "comp-arc-centre", 38),
        # T6: inner arc radius smaller than the tool radius (§3.5.3): a quarter fillet R 1 joining +x and
        # +y tangentially, r = 5 on its centre side. Both joins are smooth, one vector each, so the single
        # pair cannot be corrected (§3.5.3). (A half-circle dip R 5 with r = 6 used to be here: its 90°
        # corners give two vectors each and the manual's correction now runs the tool straight over it,
        # tests/gcode/lang/fanuc/test_compensation_interference.py.)
        ("G10 L12 P1 R5\nG00 X-20\nG01 G41 D1 X-10 Y0 F100\nX10\nG03 X11 Y1 I0 J1\nG01 Y10\nG40 X0\n",
         "comp-interference", 41),
        # T6: a groove narrower than the tool diameter (§3.5.3): 4 mm wide, r = 3.
        # (G41: going down the left side is +x, inside the groove; the walls' offsets x = 13 and x = 11 make
        # the bottom move run backwards.)
        ("G10 L12 P1 R3\nG01 G41 D1 X10 F100\nY-10\nX14\nY0\nX30\nG40 X40\n", "comp-interference", 41),
        # T6, check (b): a V groove with a small CW arc at its bottom (R 10, 2 mm wide) and r = 4: the inner
        # corners' intersections cross over, so the tool-centre arc would run the other way round.
        (
            "G10 L12 P1 R4\nG00 X-20 Y20\nG01 X-10 Y10 F100\nG41 D1 X0 Y0\nG02 X2 Y0 I1 J-10\n"
            "G01 X12 Y10\nX22 Y20\nG40 X30 Y20\n",
            "comp-interference",
            41,
        ),
        # T2: no inner intersection (§3.5.3): CCW arcs about (0,0) R5 and (4,2) R5 meet at (0,5) turning
        # left; with G41 both offset circles shrink to R 2, and centres 4.47 apart: no intersection.
        ("G10 L12 P1 R3\nG00 X5 Y-5\nG01 G41 D1 X5 Y0 F100\nG03 X0 Y5 R5\nG03 X1 Y-2 I4 J-3\n"
         "G40 G01 X10 Y-2\n", "comp-no-intersection", 33),
        # G43/G44 with no axis word (alarm 27) and offset numbers out of range (alarm 30).
        ("G43 H1\n", "length-no-axis", 27),
        ("G01 X1 D257 F100\n", "value-out-of-range", 30),
        # G10 offset value beyond ±999.999 (geometry) / ±99.999 (wear): alarm 32.
        ("G10 L12 P1 R1000\n", "bad-offset-value", 32),
        ("G10 L13 P1 R100\n", "bad-offset-value", 32),
        ("G10 L12 P0 R1\n", "bad-offset-number", 30),
        # T10: G45-G48 in G41/G42 mode (§3.5.7).
        ("G41 D1\nG45 G01 X10 F100\n", "position-offset-in-comp", None),
    ],
)  # fmt: skip
def test_compensation_alarms(text, code, alarm):
    err = program_error(text)
    assert (err.code, err.alarm) == (code, alarm), str(err)
    assert err.line > 0


def line_circle(point, direction, centre, radius, near):
    """Intersection of the line point + s·direction (unit) with a circle, the one nearest ``near``:
    |point + s·t - c|² = R² gives s² + 2 s t·w + |w|² - R² = 0 with w = point - c."""
    w = (point[0] - centre[0], point[1] - centre[1])
    half_b = direction[0] * w[0] + direction[1] * w[1]
    root = math.sqrt(half_b**2 - (w[0] ** 2 + w[1] ** 2 - radius**2))
    steps = (-half_b - root, -half_b + root)
    points = [(point[0] + s * direction[0], point[1] + s * direction[1]) for s in steps]
    return min(points, key=lambda q: math.dist(q, near))


def angle_deg(centre, point):
    return math.degrees(math.atan2(point[1] - centre[1], point[0] - centre[0]))


X60 = (
    "G10 L12 P1 R2.0\nG10 L12 P2 R6.0\nG01 G91 {side} X1000 Y0 D01 F100\nN5 G01 G91 X8000 Y2000 D01\n"
    "N6 G02 X3200 Y-1600 I-2000 J-8000 D02\nN7 G01 X2000 Y-5000\nG40 X5000\n"
)
# In the test coordinates (a start-up block G41/G42 X1000 first): N5 (1, 0) -> P = (9, 2); N6 CW about
# C = (7, -6), R = |(2, 8)| = 8.246, to Q = (12.2, 0.4) (|(5.2, 6.4)| = R: a one-quadrant arc from 76.0°
# to 50.9°, sweep -25.1°); N7 along (2, -5). r1 = 2 (D01), r2 = 6 (D02, given in N6: it applies from N6's
# end vector, §3.5.3, so N6's start vector keeps r1).
X60_P, X60_C, X60_Q, X60_R = (9.0, 2.0), (7.0, -6.0), (12.2, 0.4), math.hypot(2, 8)


def _unit(dx, dy):
    n = math.hypot(dx, dy)
    return (dx / n, dy / n)


def test_x60_interference_example_as_we_read_it():
    # §3.5.3 as printed, "(G41)": G41 puts the tool on the left, which for this CW arc (and the
    # right turns at P and Q) is the convex side: both corners are outer, the offset circles grow
    # (R + r), and the tool-centre arc keeps its quadrant. No alarm; the manual's "four quadrants" needs
    # the tool on the concave side (next test). By hand:
    out = moves(X60.format(side="G41"), dialect=_fanuc_units())
    t5 = _unit(8, 2)
    n5 = (-t5[1], t5[0])
    # N5/N6: a right turn of 28° (alpha = 152° >= 90°): the intersection of N5's left offset line (r1)
    # with N6's offset circle for r1 (R + 2), the one nearest P.
    i1 = line_circle((X60_P[0] + 2 * n5[0], X60_P[1] + 2 * n5[1]), t5, X60_C, X60_R + 2, X60_P)
    assert close(xy(out[1]), i1)
    # N6 steps radially onto its r2 circle (R + 6) and runs on it.
    radial = _unit(i1[0] - X60_C[0], i1[1] - X60_C[1])
    assert close(xy(out[2]), (X60_C[0] + (X60_R + 6) * radial[0], X60_C[1] + (X60_R + 6) * radial[1]))
    assert out[2]["line"] == out[3]["line"] == 5
    # N6/N7: a right turn of 29° (outer, obtuse): the r2 circle meets N7's left offset line (r2).
    t7 = _unit(2, -5)
    n7 = (-t7[1], t7[0])
    i2 = line_circle((X60_Q[0] + 6 * n7[0], X60_Q[1] + 6 * n7[1]), t7, X60_C, X60_R + 6, X60_Q)
    arc = out[3]
    assert arc["kind"] == "arc" and close(arc["center"][:2], X60_C)
    assert math.isclose(arc["radius"], X60_R + 6, abs_tol=1e-6)
    assert close(xy(arc), i2)
    # Both ends in the first quadrant about C (78.9° to 43.8°): a CW sweep of -35.1°, no wrap round.
    sweep = angle_deg(X60_C, i2) - angle_deg(X60_C, i1)
    assert math.isclose(arc["sweep_deg"], sweep, abs_tol=1e-6) and -36 < sweep < -35


def test_x60_with_the_tool_on_the_concave_side_is_the_manuals_check_b_alarm():
    # The manual's claim (the one-quadrant N6 "extends to four quadrants", check (b), alarm 41) holds
    # when the tool is on the concave side of the hill N5-N6-N7 (G42 here; G41 with negative D is the
    # same): both corners are inner (intersection points) and the offset circles shrink. By hand:
    t5 = _unit(8, 2)
    right5 = (t5[1], -t5[0])
    # N5/N6 with r1: N5's right offset line meets N6's r1 circle (R - 2 = 6.246) at I1, nearest P.
    i1 = line_circle((X60_P[0] + 2 * right5[0], X60_P[1] + 2 * right5[1]), t5, X60_C, X60_R - 2, X60_P)
    # N6/N7 with r2: the r2 circle (R - 6 = 2.246) meets N7's right offset line at I2, nearest Q.
    t7 = _unit(2, -5)
    right7 = (t7[1], -t7[0])
    i2 = line_circle((X60_Q[0] + 6 * right7[0], X60_Q[1] + 6 * right7[1]), t7, X60_C, X60_R - 6, X60_Q)
    # I1 lies at 71.7° about C, I2 at 79.4°: clockwise from I1 to I2 is -(360 - 7.7)° = -352.3°, against
    # the programmed -25.1°: the arc would run through all four quadrants. Each corner has one vector,
    # so there is nothing to ignore (§3.5.3): alarm 41 on N6 (line 5).
    a1, a2 = angle_deg(X60_C, i1), angle_deg(X60_C, i2)
    assert 71 < a1 < 72 and 79 < a2 < 80
    sweep = -(360.0 - (a2 - a1))
    err = program_error(X60.format(side="G42"), dialect=_fanuc_units())
    assert (err.code, err.alarm, err.line) == ("comp-interference", 41, 5)
    assert "check (b)" in str(err) and f"{sweep:.1f}" in str(err)


def test_error_names_file_and_line():
    err = program_error("G10 L12 P1 R5\nG01 G41 D1 X10 F100\nX20\nG03 X21 Y1 J1\nG01 Y10\n", file="part.nc")
    assert str(err).startswith("part.nc:4:")


# ------------------------------------------------------------------------------------------------- API
def test_initial_tool_offsets_argument():
    # interpret(..., tool_offsets=...) preloads the memory; the same path as G10 L12.
    text = "G01 G41 D1 X10 Y0 F100\nY10\nG40 X0\n"
    assert ends(text, tool_offsets={"D": {1: 2.0}}) == ends("G10 L12 P1 R2\n" + text)
    assert ends(text, tool_offsets={"D": {1: 1.5}, "D_wear": {1: 0.5}}) == ends("G10 L12 P1 R2\n" + text)
    with pytest.raises(ConfigError):
        interpret(text, tool_offsets={"Q": {1: 2.0}})
    with pytest.raises(ConfigError):
        interpret(text, tool_offsets={"D": {0: 2.0}})
    with pytest.raises(ConfigError):
        interpret(text, tool_offsets={"D": {1: "2"}})


def test_d_as_diameter_switch():
    # 2601#7 ODI: with D as a diameter, D = 4 is a 2 mm radius.
    from dataclasses import replace

    from cnc_gym.gcode import get_dialect

    gsk = get_dialect("gsk25i")
    diameter = replace(gsk, compensation=replace(gsk.compensation, d_is_diameter=True))
    text = "G01 G41 D1 X10 Y0 F100\nY10\nG40 X0\n"
    assert ends("G10 L12 P1 R4\n" + text, dialect=diameter) == ends("G10 L12 P1 R2\n" + text)


def test_g10_l12_in_g91_adds_and_wear_adds_to_geometry():
    # §3.5.5: G91 adds to the stored value; the offset in use is geometry + wear.
    text = "G01 G41 D1 X10 Y0 F100\nY10\nG40 X0\n"
    assert ends("G10 L12 P1 R1\nG91 G10 L12 P1 R0.5\nG10 L13 P1 R0.5\nG90\n" + text) == ends(
        "G10 L12 P1 R2\n" + text
    )


def test_line_to_arc_outer_obtuse_corner_is_the_intersection():
    # G41 r = 1 along +x to (10, 0), then CCW about (16, 8) (R 10; start tangent (0.8, -0.6): a right turn
    # of 37° with the tool on the left: outer, obtuse). The offset line y = 1 meets the offset circle
    # (R 10 - 1 = 9, left of a CCW arc is the centre side): (x - 16)² + 7² = 81 → x = 16 - √32.
    # End of the arc: 40° on from the start angle atan2(-8, -6).
    end_angle = math.atan2(-8, -6) + math.radians(40)
    ex, ey = 16 + 10 * math.cos(end_angle), 8 + 10 * math.sin(end_angle)
    text = (
        f"G10 L12 P1 R1\nG00 X-10\nG01 G41 D1 X0 Y0 F100\nX10\nG03 X{ex:.4f} Y{ey:.4f} I6 J8\n"
        "G01 X30\nG40 Y-10\n"
    )
    out = moves(text)
    assert close(xy(out[2]), (16 - math.sqrt(32), 1.0))
    assert out[3]["kind"] == "arc" and math.isclose(out[3]["radius"], 9.0, abs_tol=1e-9)


def test_helical_full_circle_is_compensated_in_projection():
    # §3.5.2: compensation in the plane only; the helix's Z moves with it. G41 r = 2 inside a CCW circle
    # R 10 about (0, 0), entered along +y at (10, 0): the tool runs on R 8 and drops 5 in Z over the turn.
    text = "G10 L12 P1 R2\nG00 X0 Y-20\nG01 G41 D1 X10 Y-10 F100\nX10 Y0\nG03 I-10 Z-5\nG01 X10 Y10\n"
    out = moves(text)
    arc = out[3]
    assert arc["kind"] == "arc" and math.isclose(arc["radius"], 8.0) and math.isclose(arc["sweep_deg"], 360.0)
    assert close(arc["start"], [8.0, 0.0, 0.0]) and close(arc["end"], [8.0, 0.0, -5.0])


def test_mirror_image_interchanges_g41_and_g42():
    # Fanuc rule (GSK silent): under a mirror in the plane the machine path is the mirror image of the
    # compensated program path. G51.1 X0 mirrors x → -x.
    body = "G00 X-10\nG01 G41 D1 X0 Y0 F100\nX10\nY10\nG40 X20 Y20\n"
    plain = ends("G10 L12 P1 R1\n" + body)
    mirrored = ends("G10 L12 P1 R1\nG51.1 X0\n" + body)
    assert [[-x, y] for x, y in plain] == [[x + 0.0, y] for x, y in mirrored]


def test_pure_compensate_function_gives_the_interpreter_path():
    # compensation.compensate() runs the same corner rules on plane elements without the interpreter:
    # the X57 contour as elements (start, end, centre, signed sweep) gives the same tool-centre points.
    from cnc_gym.gcode.lang.fanuc.compensation.geometry import PlaneElement, compensate

    def arc(start, end, center, ccw):
        a0 = math.atan2(start[1] - center[1], start[0] - center[0])
        a1 = math.atan2(end[1] - center[1], end[0] - center[0])
        sweep = (a1 - a0) % (2 * math.pi) if ccw else -((a0 - a1) % (2 * math.pi))
        return PlaneElement(start, end, center, sweep)

    elements = [
        PlaneElement((0, 0), (250, 550)),
        PlaneElement((250, 550), (250, 900)),
        PlaneElement((250, 900), (450, 900)),
        arc((450, 900), (500, 1150), (-150, 1150), True),
        arc((500, 1150), (900, 1150), (700, 1300), False),
        arc((900, 1150), (950, 900), (1550, 1150), True),
        PlaneElement((950, 900), (1150, 900)),
        PlaneElement((1150, 900), (1150, 550)),
        PlaneElement((1150, 550), (700, 650)),
        PlaneElement((700, 650), (250, 550)),
        PlaneElement((250, 550), (0, 0)),
    ]
    pure = [list(move.end) for move in compensate(elements, 10.0)]
    interpreted = ends(R10 + X57)
    assert len(pure) == len(interpreted)
    for a, b in zip(pure, interpreted, strict=True):
        assert close(a, b, 1e-5)  # trace records are rounded to 1e-6


X26 = """G10 L12 P1 R2
G92 X0 Y0 Z20 G69 G17
M3 S1000
G0Z2
G51 X0 Y0 I1.2 J1.2
G42 D01
M98 P2100
M98 P2200L7
G40
G50
G0 G90 Z20
X0Y0
M30
O2200
G68 X0 Y0 G91 R45.0
G90
M98 P2100
M99
O2100
G90 G0 X0 Y-20
G01Z-2 F200
X8.284
X14.142 Y-14.142
M99
"""


def test_worked_example_x26_rotated_scaled_copies_keep_the_unscaled_offset():
    # §3.2.18 (Ex.3 of G68): 8 copies of O2100 rotated by 45° each (G68 G91 R45 in O2200), scaled 1.2
    # about the origin, with G42 D01 (= 2 here) active. Scaling and rotation apply to the programmed path
    # first; the offset is not scaled (§3.2.17, §3.5.1): every N22 edge (X8.284 at Y-20) of copy k lies at
    # exactly 2 mm to the right of the edge from R_k·1.2·(0, -20) to R_k·1.2·(8.284, -20).
    # (The example sets G42 before G68, against the manual's own advice.)
    out = [r for r in moves(X26) if r["kind"] != "dwell"]
    n22 = [(i, r) for i, r in enumerate(out) if r["line"] == 22]
    assert len(n22) == 8
    for k, (i, record) in enumerate(n22):
        angle = math.radians(45 * k)
        c, s_ = math.cos(angle), math.sin(angle)
        a = (1.2 * (0 * c - (-20) * s_), 1.2 * (0 * s_ + (-20) * c))
        b = (1.2 * (8.284 * c - (-20) * s_), 1.2 * (8.284 * s_ + (-20) * c))
        n, c0 = offset_line(a, b, -2.0)  # right of the edge
        for point in (out[i - 1]["end"][:2], record["end"][:2]):  # within the 0.0001 mm rounding of
            # scaled results (§3.2.17): each coordinate is off by at most 0.00005, the distance by √2 times
            # that
            assert math.isclose(n[0] * point[0] + n[1] * point[1], c0, abs_tol=1e-4), (k, point)
        assert math.isclose(record["end"][2], -22.0)  # G01 Z-2 with G92 Z20 at machine Z0: machine -22
    assert out[-1]["end"] == [0.0, 0.0, 0.0]


def test_worked_example_x58_direction_switch_right_after_start_up():
    # §3.5.2 (figures lost, values ours): "G1G41 D_X_Y_; G42 D_X_Y_;" and the reverse. The manual also
    # says the switch is not allowed between the start-up block and the next one (§3.5.3); its own example
    # does exactly that, so we accept it with the switch rule (§3.5.3): the start-up ends where its left
    # offset meets the next block's right offset (and vice versa). r = 1.
    left_then_right = ends("G10 L12 P1 R1\nG1 G41 D1 X10 Y0 F100\nG42 D1 X20 Y10\nG40 X30 Y10\n")
    assert close(
        left_then_right[0], meet(offset_line((0, 0), (10, 0), 1.0), offset_line((10, 0), (20, 10), -1.0))
    )
    right_then_left = ends("G10 L12 P1 R1\nG1 G42 D1 X10 Y0 F100\nG41 D1 X20 Y10\nG40 X30 Y10\n")
    assert close(
        right_then_left[0], meet(offset_line((0, 0), (10, 0), -1.0), offset_line((10, 0), (20, 10), 1.0))
    )


def test_more_blocks_without_plane_motion_keep_their_order():
    # Three Z blocks after the start-up: the look-ahead starves after two; the third Z move runs at the
    # tool's compensated position, in program order, before N6.
    text = "G10 L12 P1 R5\nN1 G91 G00 G41 X50 Y50 D1\nN3 Z-10\nN4 Z-10\nN5 G01 Z-10 F100\nN6 Y100\n"
    out = moves(text)
    assert [r["line"] for r in out] == [2, 3, 4, 5, 6]
    corner = (50 - 5 / math.sqrt(2), 50 + 5 / math.sqrt(2))
    assert all(close(xy(r), corner) for r in out[:4])
    assert [r["end"][2] for r in out[1:4]] == [-10.0, -20.0, -30.0]


def test_starved_look_ahead_then_an_arc_connects_to_its_offset_start():
    # Start-up along +x to (0, 0), two Z blocks (the look-ahead starves: the start-up ends perpendicular,
    # at (0, 2)), then a CCW half circle about (5, 0) from (0, 0) to (10, 0): the tool moves straight to
    # the arc's offset start (R 5 - 2 = 3 on the centre side: (2, 0)) and runs on R 3. The arc then meets
    # the next line (+x, offset y = 2) at an outer 90° corner: x = 5 + sqrt(3² - 2²).
    out = moves(
        "G10 L12 P1 R2\nG00 X-10\nG01 G41 D1 X0 Y0 F100\nZ-1\nZ-2\nG03 X10 Y0 I5 J0\nG01 X20\nG40 X30\n"
    )
    assert [xy(r) for r in out[1:5]] == [[0.0, 2.0], [0.0, 2.0], [0.0, 2.0], [2.0, 0.0]]
    arc = out[5]
    assert arc["kind"] == "arc" and math.isclose(arc["radius"], 3.0)
    assert close(xy(arc), (5 + math.sqrt(5), 2.0))
    # Sweep: from 180° round to atan2(2, √5) + 360°, past the programmed 180° (the outer corner).
    assert math.isclose(arc["sweep_deg"], 180 + math.degrees(math.atan2(2, math.sqrt(5))), abs_tol=1e-4)


def test_g53_in_offset_mode_clears_the_vector_and_restarts():
    # §3.2.12: G53 clears the compensation. The block before it ends perpendicular ((10, 2)); the G53 rapid
    # goes to its machine position (X and Y uncommanded: the programmed (10, 0)); the next move is a new
    # start-up: (10, 0)→(20, 0) then up, a left turn (inner): x = 18, y = 2.
    out = ends(
        "G10 L12 P1 R2\nG00 X-10\nG01 G41 D1 X0 Y0 F100\nX10\nG53 G00 Z0\nG01 X20 Y0\nY10\nG40 X30 Y10\n"
    )
    assert out[2:6] == [[10.0, 2.0], [10.0, 0.0], [18.0, 2.0], [18.0, 10.0]]
