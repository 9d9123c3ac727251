"""Coordinate transforms: G68/G69 rotation, G51/G50 scaling and mirror, G51.1/G50.1, G16/G15 polar, and
the order in which they compose (§3.2.16-§3.2.18).

Expected points are worked out by hand (or with the small closed-form helpers below, which do not use
the interpreter's code): rotation p' = c + R(θ)(p - c), scaling p' = c + f·(p - c), and the manual's
order "the scaling is applied firstly and then the coordinates are rotated", the rotation centre scaled
too (§3.2.18).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from gcode_helpers import close, moves, program_error, success_share, tally
from hypothesis import given, settings
from hypothesis import strategies as st

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret


def rotate(point, centre, degrees):
    a = math.radians(degrees)
    dx, dy = point[0] - centre[0], point[1] - centre[1]
    return (centre[0] + dx * math.cos(a) - dy * math.sin(a), centre[1] + dx * math.sin(a) + dy * math.cos(a))


def ends(text: str, **kw) -> list[list[float]]:
    return [r["end"] for r in moves(text, **kw)]


def xy(rows):
    return [tuple(r[:2]) for r in rows]


def all_close(actual, expected, tol=1e-4) -> bool:
    actual, expected = list(actual), list(expected)
    if len(actual) != len(expected):
        return False
    return all(close(list(a), list(e), tol) for a, e in zip(actual, expected, strict=True))


# --------------------------------------------------------------------------- worked examples
# (docs/gsk25i_examples.md)
def test_worked_example_x24_rotated_square_with_arcs():
    # §3.2.18. G92 at machine (0, 0) makes program (-50, -50) the machine origin: machine = program + 50.
    # G68 about program (-50, -50) by 60°. The program path (absolute program coordinates):
    #   (0,0) → G91 X100 → (100,0) → G02 Y100 R100 → (100,100) → G03 X-100 I-50 J-50 → (0,100)
    #   → G01 Y-100 → (0,0): a square with a 60° CW arc of radius 100 and a 90° CCW arc about (50,50).
    text = ("G92 X-50 Y-50 G69 G17\nG68 X-50 Y-50 R60\nG90 G01 X0 Y0 F200\nG91 X100\nG02 Y100 R100\n"
            "G3 X-100 I-50 J-50\nG01 Y-100\nG69\n")  # fmt: skip
    out = moves(text)
    program_path = [(0, 0), (100, 0), (100, 100), (0, 100), (0, 0)]
    expected = [tuple(c + 50 for c in rotate(p, (-50, -50), 60)) for p in program_path]
    assert all_close(xy(r["end"] for r in out), expected)
    # The R100 arc over a chord of 100 is 60° and stays clockwise. Travelling +y along the chord, a CW
    # minor arc has its centre on the right (+x), h = sqrt(100² - 50²) from the chord's midpoint (100, 50).
    h = math.sqrt(100**2 - 50**2)
    centre = rotate((100 + h, 50), (-50, -50), 60)
    assert out[2]["kind"] == "arc" and close(out[2]["sweep_deg"], -60.0)
    assert close(out[2]["center"][:2], [centre[0] + 50, centre[1] + 50], 1e-4)
    centre = rotate((50, 50), (-50, -50), 60)
    assert out[3]["kind"] == "arc" and close(out[3]["sweep_deg"], 90.0)
    assert close(out[3]["center"][:2], [centre[0] + 50, centre[1] + 50], 1e-4)


def test_worked_example_x25_scaling_then_rotation_with_the_rotation_centre_scaled():
    # §3.2.18: G51 X300 Y150 P0.5; G68 X200 Y100 R45; a 200 x 100 rectangle from (400, 100).
    # §3.2.18: scale first, then rotate about the *scaled* rotation centre (300,150) + 0.5·((200,100) -
    # (300,150)) = (250, 125).
    text = ("G51 X300 Y150 P0.5\nG68 X200 Y100 R45\nG01 G90 X400 Y100 F100\nG91 Y100\nX-200\nY-100\nX200\n"
            "G69 G50\n")  # fmt: skip
    corners = [(400, 100), (400, 200), (200, 200), (200, 100), (400, 100)]
    scaled = [(300 + 0.5 * (x - 300), 150 + 0.5 * (y - 150)) for x, y in corners]
    expected = [rotate(p, (250, 125), 45) for p in scaled]
    assert all_close(xy(ends(text)), expected)
    # A 200 x 100 rectangle at 0.5 is 100 x 50: check one side length independently (the ends are rounded
    # to the 0.0001 mm increment while scaling is on, §3.2.17, so to within that).
    a, b = ends(text)[0], ends(text)[1]
    assert close(math.dist(a[:2], b[:2]), 50.0, 1e-4)


def test_worked_example_x22_scaling_centre_is_absolute_in_g91():
    # §3.2.17: G17 G91 G54 G0 X10 Y10 puts the tool at (10, 10). G51 X40 Y40 P2: the centre is the
    # *absolute* point (40, 40) although G91 is in force. G1 Y90 stays incremental in program
    # coordinates: program (10, 10) → (10, 100), scaled about (40, 40) by 2: (-20, 160).
    assert ends("G17 G91 G54 G0 X10 Y10\nG51 X40 Y40 P2\nG1 Y90 F100\n") == [[10.0, 10.0, 0.0],
                                                                            [-20.0, 160.0, 0.0]]


O9000 = "G00 G90 X60.0 Y60.0\nG01 X100.0 F100\nG01 Y100\nG01 X60.0 Y60.0\n"


def test_worked_example_x23_mirror_images_with_negative_scaling():
    # §3.2.17 with the subprogram O9000 written out: a triangle (60,60) (100,60) (100,100); then the
    # same under G51 X50 Y50 with I1 J-1 (mirror in Y about y=50: y' = 100 - y), I-1 J-1 (both), I-1 J1.
    text = ("G00 G90\n" + O9000 + "G51 X50.0 Y50.0 I1 J-1\n" + O9000 + "G51 X50.0 Y50.0 I-1 J-1\n" + O9000
            + "G51 X50.0 Y50.0 I-1 J1\n" + O9000 + "G50\n")  # fmt: skip
    triangle = [(60, 60), (100, 60), (100, 100), (60, 60)]
    expected = []
    for fx, fy in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
        expected += [(50 + fx * (x - 50), 50 + fy * (y - 50)) for x, y in triangle]
    # Zero-length moves give no segment: the first rapid of each copy starts where the last one ended
    # only for the first copy (tool at (60,60) already): drop repeated points from the expectation.
    got = xy(ends(text))
    dedup = [p for i, p in enumerate(expected) if i == 0 or p != expected[i - 1]]
    assert all_close(got, dedup)


def test_worked_example_x21_polar_bolt_circle_with_g81():
    # §3.2.16: G17 G90 G16; G81 X100 Y30 Z-20 R-5 F200; Y150; Y270; G15 G80; holes on R100 at
    # 30°, 150°, 270°: (86.603, 50), (-86.603, 50), (0, -100). The G91 Y120 form steps the angle.
    holes = [(100 * math.cos(math.radians(a)), 100 * math.sin(math.radians(a))) for a in (30, 150, 270)]
    for text in ("G17 G90 G16\nG81 X100 Y30 Z-20 R-5 F200\nY150\nY270\nG15 G80\n",
                 "G17 G90 G16\nG81 X100 Y30 Z-20 R-5 F200\nG91 Y120\nY120\nG15 G80\n"):  # fmt: skip
        bottoms = [tuple(r["end"][:2]) for r in moves(text) if r["kind"] == "line"]
        assert all_close(bottoms, holes)


# --------------------------------------------------------------------------- rotation
def test_repeated_g68_with_g91_r_accumulates_the_angle():
    # Explanation 3 (§3.2.18) and example 3 (§3.2.18): each G68 X0 Y0 G91 R45 turns 45° more.
    text = "".join("G68 X0 Y0 G91 R45\nG90 G00 X10 Y0\n" for _ in range(3))
    expected = [rotate((10, 0), (0, 0), 45 * k) for k in (1, 2, 3)]
    assert all_close(xy(ends(text)), expected)


def test_g68_without_centre_rotates_about_the_current_position_and_a_new_g68_replaces_the_old():
    # First G68: centre = the tool at (10, 10); program (20, 10) → (10, 20). The second G68 R90 (G90: R
    # absolute, so 90° not 180°) replaces the first, about the current *program* point (20, 10): the same
    # program point (20, 10) is now its own image, so the tool goes back to (20, 10).
    text = "G00 X10 Y10\nG68 R90\nG00 X20 Y10\nG68 R90\nX20 Y10\nX20 Y20\n"
    assert all_close(xy(ends(text)), [(10, 10), (10, 20), (20, 10), (10, 10)])


def test_g68_in_the_zx_plane_rotates_z_towards_x():
    # G18: the plane axes are (Z, X), a CCW angle turns +Z towards +X.
    assert all_close([tuple(e) for e in ends("G18 G68 X0 Z0 R90\nG01 Z10 F100\n")], [(10.0, 0.0, 0.0)])


def test_rotation_centre_in_g16_is_cartesian():
    # §3.2.16: G68's axis words are never polar.
    text = "G16\nG68 X10 Y0 R180\nG00 X0 Y0\n"  # polar (0, 0°) = program origin; rotated 180° about (10,0)
    assert all_close(xy(ends(text)), [(20.0, 0.0)])


def test_first_move_after_g69_starts_from_the_tool_position():
    # Absolute after G69 is fine; after that, G91 works again from the tool's position.
    text = "G68 X0 Y0 R90\nG01 X10 Y0 F100\nG69\nG90 X5 Y5\nG91 X1\n"
    assert all_close(xy(ends(text)), [(0.0, 10.0), (5.0, 5.0), (6.0, 5.0)])


# --------------------------------------------------------------------------- scaling and mirror
def test_g51_per_axis_factors_and_omitted_centre_is_the_current_position():
    # Tool at (10, 20); G51 I2 J3 about it: (30, 20) → (10 + 2·20, 20 + 0) = (50, 20); (10, 30) → (10, 50).
    text = "G00 X10 Y20\nG51 I2 J3\nG01 X30 Y20 F100\nX10 Y30\n"
    assert all_close(xy(ends(text)), [(10, 20), (50, 20), (10, 50)])


def test_mirror_reverses_arc_direction():
    # G51 I-1 J1 about x = 0: a CCW quarter arc from (10,0) to (0,10) about (0,0) becomes CW from (-10,0)
    # to (0,10).
    out = moves("G00 X10 Y0\nG51 X0 Y0 I-1 J1\nG00 X10 Y0\nG03 X0 Y10 R10 F100\n")
    arc = out[-1]
    assert arc["kind"] == "arc" and close(arc["sweep_deg"], -90.0) and close(arc["end"][:2], [0.0, 10.0])
    assert close(arc["center"][:2], [0.0, 0.0]) and close(arc["start"][:2], [-10.0, 0.0])


def test_programmable_mirror_g51_1_and_cancel_g50_1():
    # G51.1 X50 mirrors X about x = 50; the arc flips to CW… here CCW→CW reads as +90 → -90 in the
    # trace; G50.1 X cancels; the next absolute move is unmirrored.
    out = moves("G51.1 X50\nG01 X60 Y0 F100\nG03 X70 Y10 R10\nG50.1 X0\nG90 G01 X0 Y0\n")
    assert close(out[0]["end"][:2], [40.0, 0.0])
    assert close(out[1]["sweep_deg"], -90.0) and close(out[1]["end"][:2], [30.0, 10.0])
    assert close(out[2]["end"][:2], [0.0, 0.0])


def test_uniform_scaling_scales_arc_radius_and_keeps_the_sweep():
    out = moves("G51 X0 Y0 P2\nG01 X10 Y0 F100\nG03 X0 Y10 I-10 J0\n")
    arc = out[-1]
    assert close(arc["end"][:2], [0.0, 20.0]) and close(arc["sweep_deg"], 90.0)
    assert close(arc["center"][:2], [0.0, 0.0])


def test_unequal_scaling_gives_no_ellipse_but_a_circle_about_the_scaled_centre():
    # §3.2.17: X x2, Y x1. A full circle about (0,0) from (10,0) maps to a full circle about (0,0) from
    # (20,0): radius 20, the end back at the start.
    out = moves("G51 X0 Y0 I2 J1\nG01 X10 Y0 F100\nG03 I-10 J0\n")
    arc = out[-1]
    assert close(arc["sweep_deg"], 360.0) and close(arc["end"][:2], [20.0, 0.0])
    # A quarter arc (10,0)→(0,10) about (0,0): centre (0,0), radius 20 (the scaled start); the scaled end
    # (0,10) moves radially onto that circle: (0, 20), 90° CCW.
    out = moves("G51 X0 Y0 I2 J1\nG01 X10 Y0 F100\nG03 X0 Y10 I-10 J0\n")
    assert close(out[-1]["end"][:2], [0.0, 20.0]) and close(out[-1]["sweep_deg"], 90.0)


def test_after_g50_the_next_move_starts_from_the_tool_position():
    # §3.2.17: after G50, G91 X10 moves 10 from where the tool is (scaled point (20, 0)).
    assert all_close(xy(ends("G51 X0 Y0 P2\nG01 X10 F100\nG50\nG91 X10\n")), [(20, 0), (30, 0)])


def test_g51_without_factor_uses_the_parameter_latched_at_g51():
    # P1861 = 2000 (0.001x) = 2x via G10 L50 (§3.2.17); changing it later does not matter.
    text = ("G10 L50\nN1861 R2000\nG11\nG51 X0 Y0\nG10 L50\nN1861 R3000\nG11\nG01 X10 F100\n")
    assert ends(text) == [[20.0, 0.0, 0.0]]


def test_g68_without_r_uses_parameter_1860():
    assert all_close(xy(ends("G10 L50\nN1860 R90000\nG11\nG68 X0 Y0\nG00 X10 Y0\n")), [(0.0, 10.0)])


# --------------------------------------------------------------------------- polar
def test_polar_g91_radius_is_measured_from_the_current_position():
    # §3.2.16: with an incremental radius the origin is the current position (10, 0): radius 5 at
    # 90° → (10, 5). An absolute radius uses the work zero again.
    text = "G00 X10 Y0\nG16\nG91 X5 Y90\nG90 X10 Y180\n"
    assert all_close(xy(ends(text)), [(10, 0), (10, 5), (-10, 0)])


def test_polar_in_g18_uses_z_as_radius_and_x_as_angle():
    # G18 plane (Z, X): first word Z = radius, second X = angle from +Z towards +X.
    out = ends("G18 G16\nG00 Z10 X90\n")
    assert close(out[0], [10.0, 0.0, 0.0])


def test_polar_arcs_use_r():
    out = moves("G16\nG00 X10 Y0\nG03 X10 Y90 R10 F100\n")
    assert close(out[-1]["end"][:2], [0.0, 10.0]) and close(out[-1]["sweep_deg"], 90.0)
    assert program_error("G16\nG00 X10 Y0\nG03 X10 Y90 I-10 F100\n").code == "polar-arc-needs-r"


def test_after_g15_the_next_move_starts_from_the_tool_position():
    assert all_close(xy(ends("G16\nG00 X10 Y90\nG15\nG91 X1\n")), [(0, 10), (1, 10)])


# --------------------------------------------------------------------------- alarms and restrictions
@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("G68 X0 Y0 R30\nG18\n", "plane-change-in-rotation", None),  # §3.2.18
        ("G68 X0 Y0 R30\nG28 X0\n", "forbidden-in-rotation", None),  # §3.2.18
        ("G68 X0 Y0 R30\nG92 X0\n", "forbidden-in-rotation", None),
        ("G68 X0 Y0 R30\nG52 X1\n", "forbidden-in-rotation", None),
        ("G68 X0 Y0 R30\nG55\n", "forbidden-in-rotation", None),
        ("G68 X0 Y0 R30\nG54.1 P1\n", "forbidden-in-rotation", None),
        ("G68 X0 Y0 R30\nG53 X0\n", "forbidden-in-rotation", None),
        ("G51 X0 Y0 P2\nG28 X0\n", "forbidden-in-scaling", 109),  # §3.2.17
        ("G51 X0 Y0 P2\nG29 X0\n", "forbidden-in-scaling", 109),
        ("G51 X0 Y0 P2\nG30 X0\n", "forbidden-in-scaling", 109),
        ("G51 X0 Y0 P2\nG27 X0\n", "forbidden-in-scaling", 109),
        ("G51 X0 Y0 P2\nG56\n", "forbidden-in-scaling", 109),
        ("G51 X0 Y0 P2\nG92 X0\n", "forbidden-in-scaling", 109),
        ("G51 X0 Y0 P0\n", "bad-scale-factor", 110),
        ("G51 X0 Y0 P100\n", "bad-scale-factor", 110),
        ("G51 X0 Y0 I1 J0.0001\n", "bad-scale-factor", 110),
        ("G51 X0 Y0 P2 I2\n", "bad-combination", None),
        ("G51 X0 Y0 P2 F100\n", "g51-not-alone", None),  # §3.2.17
        ("G51 G17 X0 Y0 P2\n", "g51-not-alone", None),
        ("G68 X0 Y0 R30\nG01 X1 F100\nG69\nG91 X1\n", "incremental-after-g69", None),  # §3.2.18
        ("G68 X0 Y0 R361\n", "bad-rotation-angle", None),
        ("G68 X0 Y0 Z0 R30\n", "unused-word", None),
        ("G51.1\n", "missing-value", 5),
    ],
)  # fmt: skip
def test_transform_alarms(text, code, alarm):
    err = program_error(text)
    assert err.code == code and err.alarm == alarm


def test_restrictions_that_do_not_apply():
    # G52 is allowed in scaling mode (only G54-G59/G92/G27-G30 are named, §3.2.17); its shift is an
    # offset, added after the scaling and not scaled (§3.2.17): X1 → 2·1 + 1 = 3. G17 in G17 G68 is not a
    # plane change; G91 right after G69 with no axis word is no move.
    assert ends("G51 X0 Y0 P2\nG52 X1\nG01 X1 F100\n") == [[3.0, 0.0, 0.0]]
    # G53 in G51 mode is allowed (not named at §3.2.17); the program position follows the tool: G91 X1
    # after it is scaled about (0, 0): machine 5 + 2·1 = 7.
    assert ends("G51 X0 Y0 P2\nG53 X5\nG91 G01 X1 F100\n") == [[5.0, 0.0, 0.0], [7.0, 0.0, 0.0]]
    assert ends("G68 X0 Y0 R90\nG17 G01 X1 F100\nG69\nG91\nG90 X0 Y0\n")[-1] == [0.0, 0.0, 0.0]


# --------------------------------------------------------------------------- composition order
def expected_machine(point, *, polar, scale_centre, factors, rot_centre, angle, wcs):
    """Independent closed form of the chain: polar → scaling → rotation (centre scaled) → + G54."""
    p = np.array([point[0] * math.cos(math.radians(point[1])), point[0] * math.sin(math.radians(point[1]))]
                 if polar else point, dtype=float)  # fmt: skip
    c = np.asarray(scale_centre, float)
    f = np.asarray(factors, float)

    def scale(q):
        return c + f * (np.asarray(q, float) - c)

    a = math.radians(angle)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    centre = scale(rot_centre)
    return centre + rot @ (scale(p) - centre) + np.asarray(wcs, float)


coordinate = st.floats(-200, 200, allow_nan=False).map(lambda v: round(v, 3))
factor = st.floats(0.1, 5).map(lambda v: round(v, 3)) | st.floats(-5, -0.1).map(lambda v: round(v, 3))


@settings(max_examples=60, deadline=None)
@given(point=st.tuples(coordinate, coordinate), scale_centre=st.tuples(coordinate, coordinate),
       factors=st.tuples(factor, factor), rot_centre=st.tuples(coordinate, coordinate),
       angle=st.floats(-360, 360).map(lambda v: round(v, 3)), wcs=st.tuples(coordinate, coordinate),
       polar=st.booleans())  # fmt: skip
def test_g16_g51_g68_compose_as_the_manual_orders_them(point, scale_centre, factors, rot_centre, angle, wcs,
                                                       polar):  # fmt: skip
    text = (f"G10 L2 P1 X{wcs[0]} Y{wcs[1]}\nG54\n"
            f"G51 X{scale_centre[0]} Y{scale_centre[1]} I{factors[0]} J{factors[1]}\n"
            f"G68 X{rot_centre[0]} Y{rot_centre[1]} R{angle}\n" + ("G16\n" if polar else "")
            + f"G00 X{point[0]} Y{point[1]}\n")  # fmt: skip
    got = ends(text)
    want = expected_machine(point, polar=polar, scale_centre=scale_centre, factors=factors,
                            rot_centre=rot_centre, angle=angle, wcs=wcs)  # fmt: skip
    # Scaled results are rounded to the 0.0001 mm increment (§3.2.17): within half of it per coordinate.
    if got:  # a zero-length move gives no segment
        assert close(got[-1][:2], list(want), 5e-5 + 1e-6 * (1 + float(np.abs(want).max())))
    else:
        assert close(list(want), list(np.asarray(wcs, float) * 0), 5e-5 + 1e-6)


def test_order_matters_scaling_is_applied_before_rotation():
    # With a mirror (I-1) and a 90° rotation the two orders differ: scale-then-rotate maps (10, 0) to
    # R90·(-10, 0) = (0, -10); rotate-then-scale would give (-1·0, 10) = (0, 10).
    assert all_close(xy(ends("G51 X0 Y0 I-1 J1\nG68 X0 Y0 R90\nG00 X10 Y0\n")), [(0.0, -10.0)])


@settings(max_examples=40, deadline=None)
@given(angle=st.floats(-360, 360).map(lambda v: round(v, 3)), f=factor, mirror_x=st.booleans(),
       r=st.floats(1, 50).map(lambda v: round(v, 3)), ccw=st.booleans())  # fmt: skip
def test_arcs_stay_on_their_circle_under_similarity_transforms(angle, f, mirror_x, r, ccw):
    # Under a uniform scale (any sign), a mirror and a rotation an arc is still an arc: start and end
    # are |f|·r from the centre and the sweep keeps its size (its sign flips with an odd number of
    # mirrors).
    mirror = "G51.1 X0\n" if mirror_x else ""
    text = (f"{mirror}G51 X0 Y0 P{f}\nG68 X0 Y0 R{angle}\nG00 X{r} Y0\n"
            f"{'G03' if ccw else 'G02'} X0 Y{r if ccw else -r} R{r} F100\n")  # fmt: skip
    arc = moves(text)[-1]
    radius = abs(f) * r
    for p in (arc["start"], arc["end"]):
        assert close(math.dist(p[:2], arc["center"][:2]), radius, 1e-4)
    # A negative uniform factor is a 180° turn in the plane (det +1), not a mirror; G51.1 X is one.
    flips = mirror_x
    expected = (90.0 if ccw else -90.0) * (-1 if flips else 1)
    assert close(arc["sweep_deg"], expected, 1e-6)


@success_share(0.15)
@settings(max_examples=80, deadline=None)
@given(st.lists(st.sampled_from([
    "G68 X0 Y0 R30", "G68 R-45", "G69", "G51 X1 Y2 P2", "G51 I-1 J1", "G50", "G16", "G15", "G51.1 X5",
    "G50.1 X0", "G91", "G90", "G01 X10 Y5 F100", "G00 X-3 Y7", "G02 X5 Y5 R8 F100", "G03 X0 Y0 I-3 J0 F50",
    "X20 Y30", "G18", "G17", "G28 X0", "G92 X0", "G55", "G01 X10 Y5 F100 ,L1", "G01 X0 Y20 F100 ,R2",
    "G03 X5 Y0 R6 F100 ,R1", "G53 X1", "G60 X3 Y3", "G31 X2 F100",
]), max_size=12))  # fmt: skip
def test_random_transform_programs_give_an_error_or_a_finite_path(blocks):
    try:
        toolpath = interpret("\n".join(blocks) + "\n")
    except ProgramError as err:
        assert err.code and err.line is not None
        tally(False)
        return
    tally(True)
    assert np.isfinite(toolpath.end).all() and np.isfinite(toolpath.start).all()


X26 = """G92 X0 Y0 Z20 G69 G17
M3 S1000
G0 Z2
G51 X0 Y0 I1.2 J1.2
M98 P2100
M98 P2200 L7
G50
G0 G90 Z20
X0 Y0
M30
O2200
G68 X0 Y0 G91 R45.0
G90
M98 P2100
M99
O2100
G90 G0 X0 Y-20
G01 Z-2 F200
X8.284
X14.142 Y-14.142
M99
"""


def test_worked_example_x26_repeated_rotation_by_subprogram_under_scaling():
    # §3.2.18 without its G42 D01 / G40: the example issues G68 in cutter-compensation mode under
    # scaling, which the manual's own rule forbids (§3.2.18; docs/gsk25i_examples.md X26: quality B). O2100
    # cuts the polyline (0,-20) → (8.284,-20) → (14.142,-14.142); O2200 turns the system 45° more each call
    # (G91 R45 adds) and calls it: 8 copies in all, scaled 1.2 about (0, 0) (Z is not scaled: no K, P1862 =
    # 1). G92 Z20 at machine Z0: machine Z = program Z - 20.
    cuts = [r for r in moves(X26) if r["kind"] == "line" and r["line"] in (19, 20)]
    expected = []
    for k in range(8):
        for p in ((8.284, -20.0), (14.142, -14.142)):
            expected.append(rotate((1.2 * p[0], 1.2 * p[1]), (0.0, 0.0), 45.0 * k))
    assert all_close(xy(r["end"] for r in cuts), expected)
    assert all(r["end"][2] == -22.0 for r in cuts)


def test_inch_programs_scale_centres_and_distances_but_not_factors_or_angles():
    # G20: the G51 centre X1 is 25.4 mm, the factor 2 is a number; X2 → 25.4 + 2·(50.8 - 25.4) = 76.2.
    # G68 about (1, 0) in: X2 Y0 (50.8 mm) turned 90° about 25.4 → (25.4, 25.4). A chamfer ,L0.1 is 2.54 mm.
    assert close(ends("G20\nG51 X1 Y0 P2\nG01 X2 F10\n")[0], [76.2, 0.0, 0.0])
    assert close(ends("G20\nG68 X1 Y0 R90\nG00 X2 Y0\n")[0], [25.4, 25.4, 0.0])
    assert close(ends("G20\nG01 X1 F10 ,L0.1\nY1\n")[0], [25.4 - 2.54, 0.0, 0.0])


def test_scaled_results_are_rounded_to_the_least_increment():
    # §3.2.17 (G51 note 7): scaling results are rounded, 5 and over up, so a move may become zero.
    # X0.0001 at 0.5 → 0.00005 → rounds up to 0.0001; at 0.4 → 0.00004 → 0: no movement, no segment.
    assert ends("G51 X0 Y0 P0.5\nG01 X0.0001 F100\n") == [[0.0001, 0.0, 0.0]]
    assert ends("G51 X0 Y0 P0.4\nG01 X0.0001 F100\n") == []
    # 10.0003 at 0.5 = 5.00015 → 5.0002 (half up)
    assert close(ends("G51 X0 Y0 P0.5\nG01 X10.0003 F100\n")[0][0], 5.0002, 1e-9)
