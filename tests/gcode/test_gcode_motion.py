"""G00/G01/G02/G03/G04, planes, modality, feed and units (§2.3.5, §3.2.1-§3.2.6, §3.2.15, §3.2.19, §5).

Expected arc data are derived by hand from the geometry (stated per test), never from the code.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

import pytest
from gcode_helpers import close, moves, program_error, records

from cnc_gym.gcode import interpret
from cnc_gym.toolpath import SegmentMode


# ----------------------------------------------------------------------------- lines and modality
def test_modal_motion_feed_and_axis_only_blocks():
    # Power-on G00 (Appendix A): "X100 Y100" alone is a rapid. G01 and F stay modal; Y is kept.
    out = moves("X100 Y100\nX20 Y30\nG1 X50 Y50 F300\nX100\nZ-2\n")
    assert [r["kind"] for r in out] == ["rapid", "rapid", "line", "line", "line"]
    assert [r["end"] for r in out][-2:] == [[100.0, 50.0, 0.0], [100.0, 50.0, -2.0]]
    assert all(r["feed"] == 300.0 for r in out[2:])


def test_f_in_a_g00_block_becomes_the_cutting_feed():
    # §3.2.1 (X7): "G0 X0 Y10 F800; G1 X20 Y50;" cuts at F800.
    out = moves("G0 X0 Y10 F800\nG1 X20 Y50\n")
    assert out[0]["kind"] == "rapid" and "feed" not in out[0]
    assert out[1]["feed"] == 800.0


def test_motion_code_without_axes_only_sets_the_mode():
    out = moves("G01 F100\nG00\nX5\nG01\nX6\n")
    assert [r["kind"] for r in out] == ["rapid", "line"]


def test_incremental_and_absolute_reach_the_same_point():
    # X1 (§2.3.5): from (100, 30), "G90 G0 X40 Y70" and "G91 G0 X-60 Y40" both end at (40, 70).
    a = moves("G0 X100 Y30\nG90 G0 X40 Y70\n")[-1]["end"]
    b = moves("G0 X100 Y30\nG91 G0 X-60 Y40\n")[-1]["end"]
    assert a == b == [40.0, 70.0, 0.0]


def test_zero_length_move_makes_no_segment():
    assert len(moves("G01 X10 F100\nX10\nG00 X10\n")) == 1


def test_spindle_tool_and_coolant_are_recorded():
    tp = interpret("T3 M06\nS1200 M03\nG01 X1 F100\nM04\nX2\nM05 M09\nX3\n")
    assert list(tp.tool) == [3, 3, 3]
    assert list(tp.spindle_rpm) == [1200.0, -1200.0, 0.0]  # signed by direction: M03 +, M04 -, M05 0


def test_path_mode_flags_reach_the_segments():
    tp = interpret("G61 G01 X1 F100\nG64 X2\nG63 X3\nG62 X4\n")
    g63 = SegmentMode.OVERRIDE_LOCKED | SegmentMode.TAPPING_MODE
    assert [SegmentMode(int(m)) for m in tp.modes] == [
        SegmentMode.EXACT_STOP, SegmentMode.NONE, g63, SegmentMode.AUTO_CORNER,
    ]  # fmt: skip


# ----------------------------------------------------------------------------- units
def test_inch_program_converts_positions_and_feeds():
    # G20: 1 inch = 25.4 mm; F in inch/min → mm/min (§3.2.19).
    tp = interpret("G20\nG01 X1 Y-0.5 F10\nG91 X0.1\n")
    out = tp.to_records()
    assert close(out[0]["end"], [25.4, -12.7, 0.0]) and close(out[0]["feed"], 254.0)
    assert close(out[1]["end"], [27.94, -12.7, 0.0])
    assert all(SegmentMode(int(m)) & SegmentMode.INCH_PROGRAM for m in tp.modes)


def test_inch_arc_centre_offsets_are_converted():
    # G20 G02 from (1in, 0) with I-1: a full circle of radius 1 in = 25.4 mm about the machine origin.
    out = moves("G20\nG00 X1\nG02 I-1 F5\n")
    arc = out[-1]
    assert close(arc["center"], [0.0, 0.0, 0.0]) and close(arc["radius"], 25.4) and arc["sweep_deg"] == -360


def test_g20_in_the_same_block_applies_to_the_whole_block():
    # Units are the first item of the order of execution: "G20 G01 X1 F10" is all inch.
    out = moves("G20 G01 X1 F10\n")
    assert close(out[0]["end"][0], 25.4) and close(out[0]["feed"], 254.0)


# ----------------------------------------------------------------------------- dwell
def test_dwell_p_is_milliseconds_x_is_seconds_p_wins():
    # X13 (§3.2.6): G04 X3.8 = G04 P3800 = 3.8 s. Both given: P wins (§3.2.6).
    out = [r for r in records("G04 X3.8\nG04 P3800\nG04 P500 X9\n") if r["kind"] == "dwell"]
    assert [r["seconds"] for r in out] == [3.8, 3.8, 0.5]


def test_dwell_without_time_is_an_exact_stop():
    tp = interpret("G01 X1 F100\nG04\n")
    assert tp.to_records()[-1] == {"kind": "dwell", "line": 2, "seconds": 0.0, "modes": ["exact_stop"]}
    assert SegmentMode(int(tp.modes[-1])) & SegmentMode.EXACT_STOP


def test_dwell_errors():
    assert program_error("G04 P1.5\n").code == "decimal-point-not-allowed"  # P takes no point (§3.2.6)
    err = program_error("G04 X-1\n")
    assert (err.code, err.alarm) == ("bad-dwell", 18)  # §3.2.6
    assert program_error("G04 P-100\n").code == "bad-dwell"
    assert program_error("G04 Y1\n").code == "unused-word"


def test_dwell_does_not_move_and_its_x_is_not_an_axis():
    out = records("G00 X5\nG04 X2\nG00 Y1\n")
    assert [r["kind"] for r in out] == ["rapid", "dwell", "rapid"]
    assert out[-1]["end"] == [5.0, 1.0, 0.0]


# ----------------------------------------------------------------------------- arcs
@pytest.mark.parametrize(
    ("plane", "program", "center", "end", "sweep_deg"),
    [
        # XY (normal +Z): from +X to +Y is counter-clockwise seen from +Z (G03), +90°.
        ("XY", "G17 G00 X10\nG03 X0 Y10 I-10 F100\n", [0, 0, 0], [0, 10, 0], 90.0),
        # ... and clockwise (G02) the long way round, -270°.
        ("XY", "G17 G00 X10\nG02 X0 Y10 I-10 F100\n", [0, 0, 0], [0, 10, 0], -270.0),
        # ZX (normal +Y, u = Z, v = X): Z × X = Y, so from +Z to +X is counter-clockwise about +Y (G03).
        ("ZX", "G18 G00 Z10\nG03 X10 Z0 K-10 F100\n", [0, 0, 0], [10, 0, 0], 90.0),
        ("ZX", "G18 G00 Z10\nG02 X10 Z0 K-10 F100\n", [0, 0, 0], [10, 0, 0], -270.0),
        # YZ (normal +X, u = Y, v = Z): Y × Z = X, so from +Y to +Z is counter-clockwise about +X (G03).
        ("YZ", "G19 G00 Y10\nG03 Y0 Z10 J-10 F100\n", [0, 0, 0], [0, 0, 10], 90.0),
        ("YZ", "G19 G00 Y10\nG02 Y0 Z10 J-10 F100\n", [0, 0, 0], [0, 0, 10], -270.0),
    ],
)
def test_arcs_in_all_planes_both_directions_ijk(plane, program, center, end, sweep_deg):
    arc = moves(program)[-1]
    assert arc["kind"] == "arc" and arc["plane"] == plane
    assert close(arc["center"], center) and close(arc["end"], end) and close(arc["sweep_deg"], sweep_deg)
    assert close(arc["radius"], 10.0)


@pytest.mark.parametrize(
    ("plane_code", "plane", "axes", "offsets"),
    [("G17", "XY", ("X", "Y"), ("I", "J")), ("G18", "ZX", ("Z", "X"), ("K", "I")),
     ("G19", "YZ", ("Y", "Z"), ("J", "K"))],
)  # fmt: skip
@pytest.mark.parametrize(("code", "sign"), [("G02", -1.0), ("G03", 1.0)])
@pytest.mark.parametrize("r_sign", [1.0, -1.0])
def test_r_arcs_in_every_plane_match_the_closed_form(plane_code, plane, axes, offsets, code, sign, r_sign):
    # From (u, v) = (0, 0) to (6, 2) with |R| = 5 (the manual's X9 numbers, §3.2.3). The two circles of
    # radius 5 through both points have centres on 6u + 2v = 20, u = 3 ± sqrt(1.5). The minor arc
    # (R > 0) subtends 2·asin(sqrt(10)/5) = 78.463°, the major (R < 0) 360° minus that. Going CW (G02)
    # along the minor arc the centre lies to the right of the chord: u = 3 + sqrt(1.5), v = 10 - 3u;
    # CCW minor or CW major: the other centre.
    u_axis, v_axis = axes
    radius_word = f"R{5 * r_sign:g}"
    arc = moves(f"{plane_code} G01 F100\n{code} {u_axis}6 {v_axis}2 {radius_word}\n")[-1]
    minor = 2 * math.degrees(math.asin(math.sqrt(10) / 5))
    right_of_chord = (sign < 0) == (r_sign > 0)
    cu = 3 + math.sqrt(1.5) if right_of_chord else 3 - math.sqrt(1.5)
    cv = 10 - 3 * cu
    expected_sweep = sign * (minor if r_sign > 0 else 360 - minor)
    index = {"X": 0, "Y": 1, "Z": 2}
    centre = [0.0, 0.0, 0.0]
    centre[index[u_axis]], centre[index[v_axis]] = cu, cv
    assert arc["plane"] == plane
    assert close(arc["center"], centre) and close(arc["sweep_deg"], expected_sweep)
    assert close(arc["radius"], 5)
    # The I/J/K form with the same centre gives the same arc.
    off_u, off_v = offsets
    ijk = moves(f"{plane_code} G01 F100\n{code} {u_axis}6 {v_axis}2 {off_u}{cu:.9f} {off_v}{cv:.9f}\n")[-1]
    assert close(ijk["center"], centre, 1e-4) and close(ijk["sweep_deg"], expected_sweep, 1e-3)


def test_r_wins_over_ijk_regardless_of_order():
    # §1.3.3, §3.2.3: with R and I/J/K in one block, R is used and I/J/K are ignored.
    with_r = moves("G01 F100\nG02 I3 X6 Y2 R5 J-99\n")[-1]
    only_r = moves("G01 F100\nG02 X6 Y2 R5\n")[-1]
    assert with_r == only_r


def test_ijk_are_incremental_even_in_g90():
    # §3.2.3: centre = start + (I, J) whatever G90/G91; from (10, 5), I-10 puts it at (0, 5).
    arc = moves("G90 G00 X10 Y5\nG03 X0 Y15 I-10 F100\n")[-1]
    assert close(arc["center"], [0, 5, 0]) and close(arc["sweep_deg"], 90)


def test_full_circles_with_ijk_and_no_motion_with_r():
    # "G02 I_;" is a full circle (§3.2.3); an R arc whose end is its start is 0°: no motion (§3.2.3).
    full = moves("G00 X10\nG02 I-10 F100\n")[-1]
    assert full["sweep_deg"] == -360 and full["end"] == [10.0, 0.0, 0.0] and close(full["center"], [0, 0, 0])
    ccw = moves("G00 X10\nG03 X10 Y0 I-10 J0 F100\n")[-1]
    assert ccw["sweep_deg"] == 360
    assert moves("G00 X10\nG02 R5 F100\n") == moves("G00 X10\n")


def test_helix_full_turn_and_quarter_turn():
    # G17 helix: X/Y follow the circle, Z rises linearly (§3.2.3). Full turn of radius 10 with a
    # 2 mm drop: length sqrt((2π·10)² + 2²); F is the speed of the projected arc (§3.2.3), so the path
    # feed along the helix is F · length / planar length.
    tp = interpret("G00 X10\nG02 I-10 Z-2 F600\nG03 X0 Y10 Z0 I-10\n")
    full, quarter = tp.to_records()[1:]
    assert full["sweep_deg"] == -360 and full["end"] == [10.0, 0.0, -2.0]
    assert math.isclose(tp.length[1], math.hypot(2 * math.pi * 10, 2))
    assert math.isclose(tp.path_feed[1], 600 * math.hypot(2 * math.pi * 10, 2) / (2 * math.pi * 10))
    assert close(quarter["center"], [0, 0, -2]) and quarter["sweep_deg"] == 90
    assert quarter["end"] == [0, 10, 0]


def test_helix_in_the_zx_plane_moves_y():
    arc = moves("G18 G00 Z10\nG03 X10 Z0 Y5 K-10 F100\n")[-1]
    assert close(arc["end"], [10, 5, 0]) and arc["plane"] == "ZX" and close(arc["center"], [0, 0, 0])


def test_arc_radius_tolerance_p1810():
    # End radius 10.005 against start radius 10: within P1810 = 0.01 mm. The centre and radius are kept
    # and the end point moves radially onto the circle: (0, 10). docs/gcode.md.
    arc = moves("G00 X10\nG03 X0 Y10.005 I-10 F100\n")[-1]
    assert close(arc["center"], [0, 0, 0]) and close(arc["radius"], 10) and close(arc["end"], [0, 10, 0])
    # The next incremental move starts from there.
    assert close(moves("G00 X10\nG03 X0 Y10.005 I-10 F100\nG91 G01 X1\n")[-1]["end"], [1, 10, 0])
    err = program_error("G00 X10\nG03 X0 Y10.02 I-10 F100\n")
    assert (err.code, err.alarm, err.line) == ("arc-radius-mismatch", 20, 2)
    assert "0.0200" in err.message


def test_r_arc_chord_slightly_longer_than_the_diameter_is_a_half_circle():
    # Chord 20.005 with R10: 0.0025 over the radius, within 0.01: a half circle about the midpoint.
    arc = moves("G01 F100\nG02 X20.005 R10\n")[-1]
    assert arc["sweep_deg"] == -180 and close(arc["center"], [10.0025, 0, 0])
    err = program_error("G01 F100\nG02 X30 R10\n")
    assert (err.code, err.alarm) == ("arc-impossible", 22)


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("G02 X10 I5\n", "missing-feed", 11),  # no F ever
        ("G01 X10\n", "missing-feed", 11),
        ("G01 X10 F0\n", "missing-feed", 11),
        ("G02 X10 I5 F0\n", "zero-feed", 25),
        ("G02 X10 F100\n", "arc-missing-center", 22),
        ("G17 G02 X10 K5 F100\n", "arc-bad-offset", 21),
        ("G02 X0 Y0 R5 Z1 F100\n", "arc-impossible", 22),
        ("G02 X10 R0 F100\n", "arc-impossible", 22),
        ("G02 X10 I0 J0 F100\n", "arc-impossible", 22),
        ("G00 X10 I5\n", "unused-word", None),
        ("G01 X10 R5 F100\n", "unused-word", None),
    ],
)
def test_motion_errors(text, code, alarm):
    err = program_error(text, file="m.nc")
    assert (err.code, err.alarm, err.line) == (code, alarm, 1)


def test_worked_example_x10_arcs_absolute_radius_and_incremental():
    # §3.2.3 (X10): start (200, 40) set by G92 at the machine origin, so machine = program - (200, 40).
    # Arc 1: centre (140, 40), r 60, CCW 0° → 90°. Arc 2: centre (90, 100), r 50, CW from 0° to
    # atan2(-40, 30) = -53.1301°. The R and G91 versions describe the same two arcs.
    expected = [
        {"center": [-60.0, 0.0, 0.0], "end": [-60.0, 60.0, 0.0], "sweep_deg": 90.0, "radius": 60.0},
        {"center": [-110.0, 60.0, 0.0], "end": [-80.0, 20.0, 0.0],
         "sweep_deg": -math.degrees(math.atan2(40, 30)), "radius": 50.0},
    ]  # fmt: skip
    versions = [
        "G92 X200.0 Y40.0 Z0\nG90 G03 X140.0 Y100.0 I-60.0 F300.0\nG02 X120.0 Y60.0 I-50.0\n",
        "G92 X200.0 Y40.0 Z0\nG90 G03 X140.0 Y100.0 R60.0 F300\nG02 X120.0 Y60.0 R50.0\n",
        "G92 X200.0 Y40.0 Z0\nG91 G03 X-60.0 Y60.0 I-60.0 F300\nG02 X-20.0 Y-40.0 I-50.0\n",
        "G92 X200.0 Y40.0 Z0\nG91 G03 X-60.0 Y60.0 R60.0 F300\nG02 X-20.0 Y-40.0 R50.0\n",
    ]
    for text in versions:
        arcs = moves(text)
        assert len(arcs) == 2
        for arc, want in zip(arcs, expected, strict=True):
            assert arc["feed"] == 300.0 and arc["plane"] == "XY"
            for key, value in want.items():
                assert close(arc[key], value), (text, key, arc[key], value)


def test_x27_g20_before_the_coordinate_system_and_no_switch_later():
    # X27 (§3.2.19): ``N10 G20; N20 G92 X_ Y_;`` — G20 alone at the start, then the coordinate system is set
    # in inch: G92 X1 Y2 makes the machine origin read (1 in, 2 in), so X0 Y0 is machine (-25.4, -50.8).
    out = moves("N10 G20;\nN20 G92 X1 Y2;\nN30 G00 X0 Y0;\n")
    assert out[0]["end"][:2] == [-25.4, -50.8]
    # "Inch and metric input must not be switched during a program" (§3.2.19): after a move or a G92/G52
    # the switch is an error; repeating the mode in force (a safety line "G21 G90 G40") is not a switch.
    for text in ("G21\nG01 X1 F10\nG20\n", "G92 X1\nG20\n", "G52 X1\nG20 G00 X0\n"):
        assert program_error(text).code == "units-switch"
    assert moves("G21\nG01 X1 F10\nG21 G90 G40\nX2\n")[-1]["end"][0] == 2.0
    # G20 with the first move of the program in one block stays allowed (read first, so all inch).
    assert moves("G20 G01 X1 F10\n")[0]["end"][0] == pytest.approx(25.4)
