"""G05 P10000 / G06.2 NURBS interpolation (§3.2.5).

Expected geometry is computed independently of cnc_gym: a plain de Boor–Cox evaluation written here
(``de_boor_cox``) for the manual's example, and closed forms (circle, ellipse) for the quarter circle.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from gcode_helpers import program_error, records, success_share, tally
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cnc_gym.cli import main
from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret
from cnc_gym.toolpath import SegmentKind

# ----------------------------------------------------------------------------- the manual's example (X12)
# §3.2.5, verbatim except: (1) "K0.651784X25.768Y15.447Z0.000R5.000:" has a ':' for ';' in print;
# (2) the G05 P10000 / G05 P0 wrapper the format requires (§3.2.5) and (3) the `rank` = 4 knot-only blocks
# after the last control point (§3.2.5) are missing from the printed text (§3.2.5, X12). We add them:
# four K1.0 blocks (the last knot printed is 0.985023 < 1, and the last four knots must be equal).
_MANUAL_POINTS = """\
K0.000000X55.507Y52.139Z0.000R1.000; K0.000000X56.082Y49.615Z0.000R1.000;
K0.000000X56.780Y44.971Z0.000R1.200; K0.008286X69.575Y51.358Z0.000R1.000;
K0.014978X77.786Y58.573Z0.000R1.000; K0.036118X90.526Y67.081Z0.000R1.000;
K0.085467X105.973Y63.801Z0.000R1.000; K0.129349X100.400Y47.326Z0.000R1.000;
K0.150871X94.567Y39.913Z0.000R1.000; K0.193075X92.369Y30.485Z0.000R1.000;
K0.227259X83.440Y33.757Z0.000R2.000; K0.243467X91.892Y28.509Z0.000R1.000;
K0.256080X89.444Y20.393Z0.000R1.000; K0.269242X83.218Y15.446Z0.000R5.000;
K0.288858X87.621Y4.830Z0.000R3.000; K0.316987X80.945Y9.267Z0.000R1.000;
K0.331643X79.834Y14.535Z0.000R1.100; K0.348163X76.074Y8.522Z0.000R1.000;
K0.355261X70.183Y12.550Z0.000R1.000; K0.364853X64.171Y16.865Z0.000R1.000;
K0.383666X59.993Y22.122Z0.000R1.000; K0.400499X55.680Y36.359Z0.000R1.000;
K0.426851X56.925Y24.995Z0.000R1.000; K0.451038X59.765Y19.828Z0.000R1.000;
K0.465994X54.493Y14.940Z0.000R1.000; K0.489084X49.220Y19.828Z0.000R1.000;
K0.499973X52.060Y24.994Z0.000R1.000; K0.510862X53.305Y36.359Z0.000R1.000;
K0.533954X48.992Y22.122Z0.000R1.000; K0.548910X44.814Y16.865Z0.000R1.000;
K0.573096X38.802Y12.551Z0.000R1.000; K0.599447X32.911Y8.521Z0.000R1.000;
K0.616280X29.152Y14.535Z0.000R1.100; K0.635094X28.040Y9.267Z0.000R1.000;
K0.644687X21.364Y4.830Z0.000R3.000; K0.651784X25.768Y15.447Z0.000R5.000;
K0.668304X19.539Y20.391Z0.000R1.000; K0.682958X17.097Y28.512Z0.000R1.000;
K0.711087X25.537Y33.750Z0.000R2.000; K0.730703X16.602Y30.496Z0.000R1.000;
K0.743865X14.199Y39.803Z0.000R1.000; K0.756479X8.668Y47.408Z0.000R1.000;
K0.772923X3.000Y63.794Z0.000R1.000; K0.806926X18.465Y67.084Z0.000R1.000;
K0.849130X31.197Y58.572Z0.000R1.000; K0.870652X39.411Y51.358Z0.000R1.000;
K0.914534X52.204Y44.971Z0.000R1.200; K0.963883X52.904Y49.614Z0.000R1.000;
K0.985023X53.478Y52.139Z0.000R1.000;
"""
MANUAL_EXAMPLE = (
    "G54G40G17G49G90G21;\nG91G28Z0.0;\nG0G90X0.0Y0.0;\nX-33.22Y-15.695S0M03;\nG43Z10.H00;\nZ-21.F5000;\n"
    "G0X54.493Y52.139Z0.000;\n"
    "G05 P10000;\n"  # added (missing in print)
    "G6.2P4K0.00000X54.493Y52.139Z0.000R1.000;\n"
    + _MANUAL_POINTS
    + "K1.0;\nK1.0;\nK1.0;\nK1.0;\n"  # added: the four knot-only blocks
    + "G05 P0;\n"  # added
    + "G00 Z10.;\nM30;\n"
)


def _parse_manual():
    """Control points, weights and knots read from the example text with a regex (not the interpreter)."""
    import re

    blocks = ["K0.00000X54.493Y52.139Z0.000R1.000", *(b.strip() for b in _MANUAL_POINTS.replace("\n", "")
                                                      .split(";") if b.strip())]  # fmt: skip
    points, weights, knots = [], [], []
    for b in blocks:
        m = re.fullmatch(r"K([\d.]+)X([-\d.]+)Y([-\d.]+)Z([-\d.]+)R([\d.]+)", b)
        knots.append(float(m[1]))
        points.append([float(m[2]), float(m[3]), float(m[4])])
        weights.append(float(m[5]))
    return np.array(points), np.array(weights), np.array(knots + [1.0] * 4)


def de_boor_cox(points, weights, knots, order, t):
    """P(t) straight from the manual's definition (§3.2.5): the basis by the de Boor–Cox recursion,
    N_{i,1} = 1 on [x_i, x_{i+1}) (the last non-empty span closed at x_m), 0/0 = 0."""
    n = len(points)
    last = max(i for i in range(len(knots) - 1) if knots[i] < knots[i + 1])
    basis = [1.0 if (knots[i] <= t < knots[i + 1]) or (i == last and t == knots[-1]) else 0.0
             for i in range(len(knots) - 1)]  # fmt: skip
    for k in range(2, order + 1):
        nxt = []
        for i in range(len(knots) - k):
            a = knots[i + k - 1] - knots[i]
            b = knots[i + k] - knots[i + 1]
            left = (t - knots[i]) * basis[i] / a if a > 0 else 0.0
            right = (knots[i + k] - t) * basis[i + 1] / b if b > 0 else 0.0
            nxt.append(left + right)
        basis = nxt
    num = sum(basis[i] * weights[i] * np.asarray(points[i]) for i in range(n))
    den = sum(basis[i] * weights[i] for i in range(n))
    return num / den


def test_manual_example_x12_is_one_exact_nurbs_segment():
    tp = interpret(MANUAL_EXAMPLE)
    kinds = [SegmentKind(k).name for k in tp.kind]
    # G28 Z (to reference 1 = machine 0), G0 X0 Y0, X-33.22 Y-15.695, G43 Z10 (H00 = 0), Z-21, the G0 to the
    # first control point, the NURBS, G00 Z10.
    assert kinds.count("NURBS") == 1
    row = kinds.index("NURBS")
    assert kinds[row + 1] == "RAPID"
    curve = tp.nurbs[row]
    points, weights, knots = _parse_manual()
    assert len(points) == 50 and len(knots) == 54  # knot count = control points + rank (§3.2.5)
    assert curve.order == 4  # P4
    assert np.allclose(curve.control_points, points, atol=1e-12)
    assert np.allclose(curve.weights, weights, atol=1e-12)
    # K keeps all six decimals (a length address would truncate K0.008286 to 0.0082, §2.5).
    assert np.allclose(curve.knots, knots, atol=1e-12) and curve.knots[4] == 0.008286
    assert tp.feed[row] == 5000.0  # F5000 from the Z-21. block (modal; no F in NURBS mode)
    assert tp.line[row] == 9  # the segment belongs to the G6.2 block
    # Joined: starts where the G0 ended, ends at the last control point (clamped knots).
    assert np.allclose(tp.start[row], tp.end[row - 1]) and np.allclose(tp.start[row], [54.493, 52.139, 0.0])
    assert np.allclose(tp.end[row], [53.478, 52.139, 0.0])
    for t in (0.0, 0.003, 0.1, 0.2567, 0.5, 0.77, 0.99, 1.0):
        assert np.allclose(curve.evaluate(t)[0], de_boor_cox(points, weights, knots, 4, t), atol=1e-9), t
    # Arc length: the segment's length is the curve's, and evaluating by arc length lands on the curve.
    assert tp.length[row] == pytest.approx(curve.length)
    dense = np.linspace(0.0, 1.0, 20001)
    polyline = np.sum(np.linalg.norm(np.diff(curve.evaluate(dense), axis=0), axis=1))
    assert curve.length == pytest.approx(polyline, rel=1e-5)  # the chord sum converges from below
    s_mid = tp.s_start[row] + 0.5 * tp.length[row]
    point, _, _ = tp.evaluate(s_mid)
    distance, index, _ = tp.nearest(point)
    assert index[0] == row and distance[0] < 1e-6


# ----------------------------------------------------------------------------- a quarter circle
R = 10.0
# Weight of the middle control point of a rational quadratic 90° arc, √½, to 13 decimals: "R0.7071067811865"
# is 16 characters, the longest word the GSK 25i takes (alarm 13); the 5e-14 error is far below every check.
HALF_SQRT2 = "0.7071067811865"
QUARTER = f"""G05 P10000
G00 X10 Y0 Z0
G06.2 P3 K0 X10 Y0 F600
K0 X10 Y10 R{HALF_SQRT2}
K0 X0 Y10
K1
K1
K1
G01 X-5
G05 P0
M30
"""


def test_quarter_circle_matches_the_closed_form():
    tp = interpret(QUARTER)
    row = int(np.flatnonzero(tp.kind == SegmentKind.NURBS)[0])
    # Length of a quarter circle: πR/2.
    assert tp.length[row] == pytest.approx(math.pi * R / 2, abs=1e-9)
    # (the boundary s = end belongs to the next segment, so stop a hair before it)
    s = tp.s_start[row] + np.linspace(0.0, tp.length[row] - 1e-9, 41)
    point, tangent, curvature = tp.evaluate(s)
    angle = (s - tp.s_start[row]) / R  # arc length = R·angle from (R, 0)
    assert np.allclose(point[:, 0], R * np.cos(angle), atol=1e-7)
    assert np.allclose(point[:, 1], R * np.sin(angle), atol=1e-7)
    assert np.allclose(tangent[:, :2], np.column_stack((-np.sin(angle), np.cos(angle))), atol=1e-7)
    assert np.allclose(curvature, 1.0 / R, rtol=1e-7)
    # Nearest point: (20, 20) is 20√2 - R from the arc, at 45°; (0, -5) is nearest to the start (R, 0)? No:
    # the arc runs 0°..90°, so the nearest point of the arc to (0, -5) is its start (10, 0): √125.
    distance, _, _ = tp.nearest(np.array([[20.0, 20.0, 0.0], [0.0, -5.0, 0.0]]), row, row + 1)
    assert distance[0] == pytest.approx(20 * math.sqrt(2) - R, abs=1e-7)
    assert distance[1] == pytest.approx(math.sqrt(125.0), abs=1e-7)
    # The next block starts at the curve's end: G01 X-5 from (0, 10).
    assert np.allclose(tp.start[row + 1], [0.0, 10.0, 0.0])
    assert np.allclose(tp.end[row + 1], [-5.0, 10.0, 0.0])


def test_incremental_form_gives_the_same_curve():
    # §3.2.5: in G91 the first control point is written X0 Y0 Z0; later points are relative to the previous.
    text = (QUARTER.replace("G06.2 P3 K0 X10 Y0 F600\nK0 X10 Y10", "G91 G06.2 P3 K0 X0 Y0 Z0 F600\nK0 X0 Y10")
            .replace("K0 X0 Y10\nK1", "K0 X-10 Y0\nK1").replace("G01 X-5", "G90 G01 X-5"))  # fmt: skip
    a, b = interpret(QUARTER), interpret(text)
    ra, rb = (int(np.flatnonzero(t.kind == SegmentKind.NURBS)[0]) for t in (a, b))
    assert np.allclose(a.nurbs[ra].control_points, b.nurbs[rb].control_points)


def test_transforms_map_the_control_points_exactly():
    # G51 with X×2, Y×1 about the origin, and a G54 offset of (100, 50, 5): the quarter circle becomes the
    # quarter ellipse x = 100 + 20 cos θ, y = 50 + 10 sin θ exactly (an affine map of the control points
    # is exact for NURBS, unlike arcs under unequal scaling).
    # (G51 keeps the tool where it is, §3.2.17: the G00 after it moves it to the image of (10, 0).)
    text = "G10 L2 P1 X100 Y50 Z5\nG54\n" + (
        QUARTER.replace("G00 X10 Y0 Z0", "G51 X0 Y0 I2 J1\nG00 X10 Y0 Z0")
        .replace("G01 X-5\nG05 P0", "G01 X-5\nG50\nG05 P0"))  # fmt: skip
    tp = interpret(text)
    row = int(np.flatnonzero(tp.kind == SegmentKind.NURBS)[0])
    point = tp.nurbs[row].evaluate(np.linspace(0.0, 1.0, 33))
    assert np.allclose(((point[:, 0] - 100) / 20) ** 2 + ((point[:, 1] - 50) / 10) ** 2, 1.0, atol=1e-12)
    assert np.allclose(point[:, 2], 5.0)
    assert np.allclose(tp.start[row], [120.0, 50.0, 5.0]) and np.allclose(tp.end[row], [100.0, 60.0, 5.0])
    # G68 by 90°: the arc from (10, 0) to (0, 10) turns into the arc from (0, 10) to (-10, 0).
    tp = interpret(QUARTER.replace("G00 X10 Y0 Z0", "G68 X0 Y0 R90\nG00 X10 Y0 Z0")
                   .replace("G01 X-5\nG05 P0", "G01 X-5\nG69\nG05 P0"))
    row = int(np.flatnonzero(tp.kind == SegmentKind.NURBS)[0])
    assert np.allclose(tp.start[row], [0.0, 10.0, 0.0]) and np.allclose(tp.end[row], [-10.0, 0.0, 0.0])
    point = tp.nurbs[row].evaluate(np.linspace(0.0, 1.0, 9))
    assert np.allclose(np.hypot(point[:, 0], point[:, 1]), R)


def test_tool_length_offset_moves_the_curve():
    # G43 H1 = 25 mm (type B in G17: on Z): every control point is 25 mm higher in machine coordinates.
    text = QUARTER.replace("G00 X10 Y0 Z0", "G43 H1 Z0\nG00 X10 Y0 Z0")
    tp = interpret(text, tool_offsets={"H": {1: 25.0}})
    row = int(np.flatnonzero(tp.kind == SegmentKind.NURBS)[0])
    assert np.allclose(tp.nurbs[row].control_points[:, 2], 25.0)


def test_g20_weights_and_knots_are_numbers_not_lengths():
    # In G20 the control points are inch (×25.4), the weight and the knots are not converted.
    text = "G20\n" + QUARTER.replace("F600", "F20")
    tp = interpret(text)
    row = int(np.flatnonzero(tp.kind == SegmentKind.NURBS)[0])
    curve = tp.nurbs[row]
    assert np.allclose(curve.control_points[:, :2], [[254, 0], [254, 254], [0, 254]])
    assert np.allclose(curve.weights, [1.0, math.sqrt(0.5), 1.0])
    assert np.allclose(curve.knots, [0, 0, 0, 1, 1, 1])
    assert tp.feed[row] == pytest.approx(20 * 25.4)


def test_omitted_axis_keeps_the_previous_control_point():
    # Z named in the first control point is an axis of the curve; a later block without Z keeps it.
    text = "G05 P10000\nG00 X0 Y0 Z1\nG06.2 P2 K0 X0 Y0 Z1 F100\nK0 X5\nK1 Y5 Z3\nK2\nK2\nG01 X0\n"
    tp = interpret(text)
    row = int(np.flatnonzero(tp.kind == SegmentKind.NURBS)[0])
    assert np.allclose(tp.nurbs[row].control_points, [[0, 0, 1], [5, 0, 1], [5, 5, 3]])
    # Rank 2 is the control polygon itself: length 5 + √(25 + 4).
    assert tp.length[row] == pytest.approx(5 + math.sqrt(29), abs=1e-9)


def test_two_curves_and_axes_in_the_second_block():
    # "When there is no command in the first block, the axes should be specified in the second" (§3.2.5).
    text = ("G05 P10000\nG00 X0 Y0\nG06.2 P2 F100\nK0 X0 Y0\nK0 X4 Y0\nK1\nK1\n"
            "G06.2 P2 K0 X4 Y0\nK0 X4 Y3\nK1\nK1\nG05 P0\nG00 X0\n")  # fmt: skip
    recs = records(text)
    nurbs = [r for r in recs if r["kind"] == "nurbs"]
    assert len(nurbs) == 2 and nurbs[0]["end"] == nurbs[1]["start"] == [4.0, 0.0, 0.0]
    assert nurbs[0]["order"] == 2 and nurbs[1]["line"] == 8


def test_trace_prints_nurbs_records(tmp_path, capsys):
    program = tmp_path / "quarter.nc"
    program.write_text(QUARTER)
    assert main(["trace", str(program)]) == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    rec = next(r for r in lines if r["kind"] == "nurbs")
    assert rec["line"] == 3 and rec["order"] == 3 and rec["feed"] == 600.0
    assert rec["control_points"] == [[10.0, 0.0, 0.0], [10.0, 10.0, 0.0], [0.0, 10.0, 0.0]]
    assert rec["knots"] == [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]
    assert rec["weights"][1] == pytest.approx(math.sqrt(0.5))


# ----------------------------------------------------------------------------- restrictions
_HEAD = "G05 P10000\nG00 X10 Y0 Z0\n"
_CURVE = "G06.2 P3 K0 X10 Y0 F600\nK0 X10 Y10 R0.7\nK0 X0 Y10\nK1\nK1\nK1\n"


@pytest.mark.parametrize(
    ("text", "code", "line"),
    [
        ("G00 X10 Y0\n" + _CURVE, "nurbs-outside-hpcc", 2),  # no G05 P10000 (§3.2.5)
        ("G05 P10000\nD1 G41 G01 X10 Y0 F100\n" + _CURVE, "nurbs-in-compensation", 3),  # §3.2.5
        (_HEAD + _CURVE.replace("K0 X10 Y0 F600", "K0 X11 Y0 F600"), "nurbs-start-point", 3),  # §3.2.5
        (_HEAD + _CURVE.replace("P3", "P5"), "nurbs-bad-rank", 3),  # P 2..4 (§3.2.5)
        (_HEAD + _CURVE.replace("K0 X0 Y10", "P3 K0 X0 Y10"), "nurbs-forbidden", 5),  # P: first block only
        (_HEAD + _CURVE.replace("K0 X0 Y10", "K0 X0 Y10 F300"), "nurbs-forbidden", 5),  # no feed change
        (_HEAD + _CURVE.replace("K0 X0 Y10", "K0 X0 Y10 M08"), "nurbs-forbidden", 5),  # no M/S/T/B (§3.2.5)
        (_HEAD + _CURVE.replace("K0 X0 Y10", "K0 X0 Y10 S100"), "nurbs-forbidden", 5),
        (_HEAD + _CURVE.replace("K0 X0 Y10", "G90 K0 X0 Y10"), "nurbs-forbidden", 5),  # no G codes
        (_HEAD + _CURVE.replace("K1\nK1\nK1\n", "K1\nG01 X5\n"), "nurbs-incomplete", 7),  # curve not finished
        (_HEAD + _CURVE.replace("K1\nK1\nK1\n", "K1\nG05 P0\n"), "nurbs-incomplete", 7),  # before G05 P0
        (_HEAD + _CURVE.replace("K1\nK1\nK1\n", "K1\nK1\n"), "nurbs-incomplete", 3),  # program ends inside
        (_HEAD + _CURVE.replace("K0 X0 Y10", "X0 Y10"), "nurbs-missing-knot", 5),  # one knot per block
        (_HEAD + _CURVE.replace("K1\nK1\nK1\n", "K1\nK1 X3 Y3\nK1\nK1\n"), "nurbs-missing-knot", 7),
        (_HEAD + _CURVE.replace("K0 X10 Y10", "K-1 X10 Y10"), "nurbs-bad-knot", 4),  # non-decreasing
        (_HEAD + _CURVE.replace("K0 X0 Y10", "K0.5 X0 Y10"), "nurbs-bad-curve", 8),  # unclamped start
        (_HEAD + _CURVE.replace("K1\nK1\nK1\n", "K1\nK1\nK2\n"), "nurbs-bad-curve", 8),  # unclamped end
        (_HEAD + _CURVE.replace("R0.7", "R0"), "nurbs-bad-weight", 4),
        (_HEAD + _CURVE.replace("K0 X0 Y10", "K0 X0 Y10 Z5"), "nurbs-axes", 5),  # Z not in the first block
        (_HEAD + _CURVE + "K1 X3 Y4\n", "nurbs", 9),  # after the curve: a new one needs G06.2
        (_HEAD + _CURVE + "G05 P0\nX5 Y5\n", "nurbs-outside-hpcc", 10),  # G06.2 modal, contour control off
        (_HEAD + _CURVE.replace("K0 X0 Y10", "M98 P1000\nK0 X0 Y10"), "nurbs-forbidden", 5),  # a call
        (_HEAD + _CURVE.replace("K0 X0 Y10", "G65 P1000 A1\nK0 X0 Y10"), "nurbs-forbidden", 5),
        ("G05 P1\n", "bad-g05", 1),
        ("G05 P10000 X1\n", "bad-g05", 1),
        ("G05 P10000\nG16\nG00 X10 Y0\n" + _CURVE, "nurbs", 4),  # polar input
    ],
)  # fmt: skip
def test_nurbs_restrictions(text, code, line):
    err = program_error(text)
    assert err.code == code and err.line == line, str(err)


def test_at_most_p1407_blocks_per_curve():
    # P1407 = 200 blocks of one curve: 197 control points + 4 knot-only blocks = 201 blocks (rank 4).
    def program(points: int) -> str:
        # knots 0, 0, 0, 0, 0.001, 0.002, … (clamped), then four K1
        body = "".join(f"K{max(i - 3, 0) * 0.001:.3f} X{10 + i} Y0\n" for i in range(1, points))
        return _HEAD + "G06.2 P4 K0 X10 Y0 F600\n" + body + "K1\n" * 4

    err = program_error(program(197))
    assert err.code == "nurbs-too-long" and err.line == 3 + 197 + 3  # the 201st block of the curve
    ok = program(196)
    tp = interpret(ok)
    assert (tp.kind == SegmentKind.NURBS).sum() == 1


def test_canned_cycle_ends_at_g06_2():
    # G06.2 is a group-01 code: it ends a canned cycle like G01 (§3.4.4).
    text = "G81 X0 Y0 Z-5 R2 F100\nG05 P10000\nG06.2 P2 K0 X0 Y0 Z0\nK0 X5 Y0\nK1\nK1\nG01 X0\n"
    tp = interpret(text)
    assert (tp.kind == SegmentKind.NURBS).sum() == 1


_coordinate = st.floats(-5, 5, allow_nan=False).map(lambda v: round(v, 3))
_weight = st.one_of(st.none(), st.sampled_from([0.5, 1, 2, 0.01, 30]))
_control_point = st.tuples(_coordinate, _coordinate, _weight)


@success_share(0.2)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(_control_point, min_size=2, max_size=10),
       st.lists(st.floats(0.05, 0.95).map(lambda v: round(v, 2)), max_size=10),
       st.lists(st.tuples(st.integers(0, 20), st.sampled_from(["K0.5", "X1", "R2", "P1", "F100", "G01", "M08",
                                                               "", "K-1", "R0", "K2 X1"])),
                max_size=2))  # fmt: skip
def test_random_nurbs_programs_give_an_error_or_a_finite_path(points, inner, noise):
    # Mostly well-formed curves (rank 3: knots 0 0 0, sorted inner knots, 1 1 1; random points and
    # weights) with now and then a stray or broken block: an error, or a finite path.
    knots = [0.0, 0.0, *sorted(inner)][: len(points)]
    missing = len(points) - len(knots)
    knots += [round(knots[-1] + (1 - knots[-1]) * (k + 1) / (missing + 1), 6) for k in range(missing)]
    lines = [_HEAD, "G06.2 P3 K0 X10 Y0 F600\n"]
    for (x, y, weight), knot in zip(points, knots, strict=True):
        lines.append(f"K{knot} X{x} Y{y}" + (f" R{weight}" if weight is not None else "") + "\n")
    lines.append("K1\nK1\nK1\nG01 X0\n")
    for position, word in noise:
        lines.insert(2 + position % (len(lines) - 1), word + "\n")
    try:
        tp = interpret("".join(lines))
    except ProgramError:
        tally(False)
        return
    tally(True)
    assert np.all(np.isfinite(tp.end)) and np.isfinite(tp.total_length)


def test_extreme_weights_are_rejected_and_small_ones_are_cheap():
    # R0.01 beside R1 (the 8-line program) is a fine curve: its length table stays small.
    text = _HEAD + "G06.2 P3 K0 X10 Y0 F600\nK0 X20 Y0 R0.01\nK0 X20 Y10 R1\nK0.5 X10 Y10 R0.01\nK1\nK1\nK1\n"
    tp = interpret(text)
    assert len(tp.nurbs[1]._leaf_t) < 200
    # Weights more than a factor 1e6 apart cannot be evaluated to the path's accuracy: an error at the
    # block that widens the range beyond it.
    text = _HEAD + "G06.2 P4 K0 X10 Y0 R0.0001 F600\nK0 X20 Y0 R1000\nK0 X20 Y10\nK0 X10 Y10\n" + "K1\n" * 4
    err = program_error(text)
    assert (err.code, err.line) == ("nurbs-bad-weight", text.split("\n").index("K0 X20 Y0 R1000") + 1)
