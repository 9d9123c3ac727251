"""The worked examples of the Syntec 8.20 mill programming manual as golden tests (docs/syntec_examples.md
indexes them: one row per example, E1-E46).

Each test runs the manual's program (its ``//`` comments dropped where they only repeat the block, lines
lost to the text conversion re-joined; a repair is named in the test and in the index) and compares the tool
path with expectations worked out by hand from the manual's text — points, centres, radii, lengths and
times written out below with the reasoning, never taken from the interpreter. Where the manual contradicts
itself the test follows the reading its own examples support, and says so.
"""

from __future__ import annotations

import math

import pytest
from gcode_helpers import compact

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret
from cnc_gym.machine import AxisConfig, MachineConfig


def run(text: str, **kw):
    return interpret(text, dialect="syntec", **kw)


def records(text: str, **kw) -> list[dict]:
    return run(text, **kw).to_records()


def path(text: str, **kw) -> list[tuple]:
    """The tool path as compact rows (gcode_helpers.compact)."""
    return compact(records(text, **kw))


def error(text: str, **kw) -> ProgramError:
    with pytest.raises(ProgramError) as info:
        run(text, **kw)
    return info.value


def close(a, b, tol: float = 1e-3) -> bool:
    return all(math.isclose(x, y, abs_tol=tol) for x, y in zip(a, b, strict=True))


def polar_point(r: float, degrees: float, centre=(0.0, 0.0)) -> tuple[float, float]:
    return (centre[0] + r * math.cos(math.radians(degrees)), centre[1] + r * math.sin(math.radians(degrees)))


def r_centre(start, end, r: float, ccw: bool) -> tuple[float, float]:
    """Centre of the R arc (R > 0: the short way) from ``start`` to ``end``, worked out from the chord."""
    mx, my = (start[0] + end[0]) / 2, (start[1] + end[1]) / 2
    dx, dy = end[0] - start[0], end[1] - start[1]
    chord = math.hypot(dx, dy)
    h = math.sqrt(max(r * r - chord * chord / 4, 0.0))
    # For a short CCW arc the centre is on the left of the chord.
    side = 1.0 if ccw else -1.0
    return (mx - side * h * dy / chord, my + side * h * dx / chord)


# ---------------------------------------------------------------------- §G00, §G01, §G90/G91
def test_e1_absolute_and_incremental_one_liners_reach_the_same_point():
    """§G00 / §G01 examples 1: from the start (20, 20) (the figure is lost; both forms agree on it),
    ``G90 X90.0 Y40.0`` and ``G91 X70.0 Y20.0`` both end at (90, 40). The G01 forms carry no F: the
    default feed, 1000 mm/min (§G01 "Default value F"), applies."""
    start = "G00 X20. Y20.\n"
    for block in ("G90 G00 X90.0 Y40.0 ;", "G91 G00 X70.0 Y20.0 ;"):
        assert path(start + block)[-1] == ("R", (90.0, 40.0, 0.0))
    for block in ("G90 G01 X90.0 Y40.0 ;", "G91 G01 X70.0 Y20.0 ;"):
        assert path(start + block)[-1] == ("F", (90.0, 40.0, 0.0), 1000.0)


POLYGON_ABSOLUTE = """N001 G00 X0.0 Y0.0 Z10.0 ; //positioning to above of P0
N002 G90 G01 Z-10.0 F1000 ;
N003 Y38.0 ; //P0 → P1
N004 X20.0 Y45.0 ;
N005 X55.0 ;
N006 Y10.0 ;
N007 X45.0 Y0.0 ;
N008 X0.0 ;
N009 G00 Z10.0 ;
N010 M30 ;
"""
POLYGON_INCREMENTAL = """N001 G00 X0.0 Y0.0 Z10.0 ;
N002 G91 G01 Z-20.0 F1000 ;
N003 Y38.0 ;
N004 X20.0 Y7.0 ;
N005 X35.0 ;
N006 Y-35.0 ;
N007 X-10.0 Y-10.0 ;
N008 X-45.0 ;
N009 G00 Z20.0 ;
N011 M30 ;
"""


def test_e2_polygon_absolute_and_incremental_are_the_same_path():
    """§G01 example 2: P0 (0, 0) → P1 (0, 38) → P2 (20, 45) → P3 (55, 45) → P4 (55, 10) → P5 (45, 0) →
    P0 at Z-10, F1000. The incremental program's increments add up to the same points (38 = 38; 0 + 20,
    38 + 7 = (20, 45); …), and its block numbers jump N009 → N011 (a numbering quirk, not an error). Cut
    length 20 (plunge) + 38 + √(20² + 7²) + 35 + 35 + √(10² + 10²) + 45 = 208.332 mm, 12.5 s at F1000."""
    corners = [(0, 0, -10), (0, 38, -10), (20, 45, -10), (55, 45, -10), (55, 10, -10), (45, 0, -10),
               (0, 0, -10)]  # fmt: skip
    expected = [("R", (0.0, 0.0, 10.0))] + [("F", tuple(float(c) for c in p), 1000.0) for p in corners]
    expected.append(("R", (0.0, 0.0, 10.0)))
    assert path(POLYGON_ABSOLUTE) == expected
    assert path(POLYGON_INCREMENTAL) == expected
    tp = run(POLYGON_ABSOLUTE)
    cut = sum(tp.length[i] for i in range(len(tp)) if tp.kind[i] == 1)
    assert math.isclose(cut, 20 + 38 + math.hypot(20, 7) + 35 + 35 + math.hypot(10, 10) + 45, abs_tol=1e-9)
    assert math.isclose(cut, 208.332, abs_tol=5e-4)
    assert math.isclose(cut / 1000.0 * 60.0, 12.5, abs_tol=1e-3)


# ---------------------------------------------------------------------- §G02/G03
def test_e3_arc_in_least_units_absolute_end_is_off_the_circle():
    """§G02/G03 example 1: numbers without a decimal point are µm, so X5500 Y4000 is (5.5, 4.0) mm and
    I-3000 J-1000 put the centre at (2.5, 3.0), radius √(3² + 1²) = 3.1623 mm. The absolute block ends at
    (1.5, 4.0), 1.4142 mm from the centre: 1.748 mm off the circle, so it is an alarm (the manual's
    figure would have shown Y6000). The commented incremental alternative ends at (5.5 - 4, 4 + 2) =
    (1.5, 6.0), which is on the circle: a CCW quarter (from 18.43° to 108.43°)."""
    absolute = "G90 G00 X5500 Y4000;\nG17 G90 G03 X1500 Y4000 I-3000 J-1000 F200;\n"
    assert error(absolute).code == "arc-radius-mismatch"
    incremental = "G90 G00 X5500 Y4000;\n(G17 G90 G03 X1500 Y4000 I-3000 J-1000 F200;)\n" \
                  "G17 G91 G03 X-4000 Y2000 I-3000 J-1000 F200;\n"  # fmt: skip
    assert path(incremental) == [("R", (5.5, 4.0, 0.0)),
                                 ("A", (1.5, 6.0, 0.0), (2.5, 3.0, 0.0), round(math.sqrt(10), 3), 90.0)]


def test_e4_full_circle_radius_is_one_millimetre():
    """§G02/G03 example 2: ``G02 I1000`` is I = 1.000 mm (µm without a point): a clockwise full circle about
    (1, 0), radius 1 mm, 2π mm long, 2π / 100 min = 3.77 s at F100 (a naive reading would give 1 m)."""
    tp = run("G90 G00 X0 Y0;\nG02 I1000 F100; //interpolate a full circle\n")
    assert path("G90 G00 X0 Y0;\nG02 I1000 F100;\n") == [("A", (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 1.0, -360.0)]
    assert math.isclose(tp.length[0], 2 * math.pi, abs_tol=1e-12)
    assert math.isclose(tp.length[0] / 100.0 * 60.0, 3.77, abs_tol=5e-3)


def test_e5_helix_quarter_turn():
    """§G02/G03 helical example: ``G17 G03 X0.0 Y1000.0 R1000.0 Z900.0 F600`` from (1000, 0, 0) (the figure
    is lost; the quarter turn needs this start) is a CCW quarter circle about the origin, radius 1000,
    Z rising 900: projected length 1570.8 mm, helix length √(1570.8² + 900²) = 1810.4 mm. F is taken
    along the projection (the Fanuc convention; the manual is silent): 157.1 s at F600."""
    tp = run("G00 X1000. Y0 Z0\nG17 G03 X0.0 Y1000.0 R1000.0 Z900.0 F600 ;\n")
    assert path("G00 X1000. Y0 Z0\nG17 G03 X0.0 Y1000.0 R1000.0 Z900.0 F600 ;\n")[-1] == (
        "A", (0.0, 1000.0, 900.0), (0.0, 0.0, 0.0), 1000.0, 90.0)
    assert math.isclose(tp.planar_length[1], 500 * math.pi, abs_tol=1e-9)
    assert math.isclose(tp.length[1], math.hypot(500 * math.pi, 900), abs_tol=1e-9)
    assert math.isclose(tp.length[1], 1810.4, abs_tol=0.05)
    assert math.isclose(tp.length[1] / tp.path_feed[1] * 60.0, 157.08, abs_tol=0.01)


# ---------------------------------------------------------------------- §G04
def test_e6_dwell_times():
    """§G04: ``X2500`` 2.5 s (ms without a point), ``X2.5`` 2.5 s, ``P2500`` 2.5 s, and ``P2.5`` "delay 2 sec
    (decimal point not permitted)": the manual's own reading, the fraction dropped and the rest seconds."""
    text = "G04 X2500;//delay 2.5 sec\nG04 X2.5;\nG04 P2500;\nG04 P2.5;//delay 2 sec\n"
    assert path(text) == [("D", 2.5), ("D", 2.5), ("D", 2.5), ("D", 2.0)]


# ---------------------------------------------------------------------- §G05, §G05.1, §G06.2
G05_POINTS = [(3.8, 6.1), (4.6, 7.0), (5.4, 6.1), (6.1, 4.0), (6.9, 1.9), (7.7, 1.0), (8.5, 1.9), (9.3, 4.0),
              (10.0, 6.1)]  # fmt: skip


def test_e7_g05_high_speed_polyline():
    """§G05 example: from (3, 4) nine G01 blocks at F5000 (the maximum feed in G05) through the points above,
    about y = 4 + 3·sin(x - 3). Every block runs; the chords add up to 15.986 mm (0.192 s at a constant
    5000 mm/min); every G01 row of the G05 region carries the smoothing tolerance of parameter set P10000
    (0.01 mm, ``SyntecOptions``) and the feed 5000 as its maximum; the rapid before G05 carries none."""
    text = ("G0 X3. Y4. Z0.\nG05 P10000 //Start high speed & high precision\nG01 X3.8 Y6.1 F5000.\nX4.6 Y7.\n"
            "X5.4 Y6.1\nX6.1 Y4.\nX6.9 Y1.9\nX7.7 Y1.\nX8.5 Y1.9\nX9.3 Y4.\nX10. Y6.1\n"
            "G05 P0 // Cancel high speed & high precision interpolation\nM30\n")  # fmt: skip
    tp = run(text)
    assert [r[1][:2] for r in path(text)[1:]] == G05_POINTS
    chords = [math.dist(a, b) for a, b in zip([(3.0, 4.0), *G05_POINTS], G05_POINTS, strict=False)]
    assert math.isclose(sum(tp.length), sum(chords) + 5.0, abs_tol=1e-9)  # + the rapid (3, 4) from (0, 0)
    assert math.isclose(sum(chords), 15.986, abs_tol=1e-3)
    assert tp.feed[1:].tolist() == [5000.0] * 9
    assert tp.smoothing_tolerance_mm.tolist() == [0.0] + [0.01] * 9


G051_EX1 = """N001 G05.1 Q1 E0.01 //Start path smoothing function, allowable error: 10um
N002 G90 G01 F2000
N003 X-0.002 Y-0.001
N004 X-0.003 Y-0.003
N005 X-0.004 Y-0.005
N006 X-0.005 Y-0.007
N007 X-0.007 Y-0.008
N008 X-0.008 Y-0.009
N009 X-0.011 Y-0.010
N010 X-0.013 Y-0.012
N011 X-0.014 Y-0.013
N012 X-0.015 Y-0.015
N013 X-0.016 Y-0.018
N014 G05.1 Q0 // close path smoothing function
N015 M30 //program ends
"""
G051_EX2_STEPS = [(-0.002, -0.001), (-0.001, -0.002), (-0.001, -0.002), (-0.001, -0.002), (-0.002, -0.001),
                  (-0.001, -0.001), (-0.003, -0.001), (-0.002, -0.002), (-0.001, -0.001), (-0.001, -0.002),
                  (-0.001, -0.003)]  # fmt: skip


def test_e8_g05_1_absolute_and_incremental_examples_are_one_path():
    """§G05.1 examples 1 and 2: eleven µm-sized G01 blocks at F2000 with E0.01 (10 µm). Example 2's
    increments are exactly example 1's differences from (0, 0): the same points, 25.4 µm in all; every
    G01 row carries the 10 µm tolerance, and G05.1 Q0 ends it."""
    incremental = G051_EX1.replace("G90 G01", "G91 G01")
    lines = incremental.splitlines()
    for k, (dx, dy) in enumerate(G051_EX2_STEPS):
        lines[2 + k] = f"N{3 + k:03d} X{dx:.3f} Y{dy:.3f}"
    incremental = "\n".join(lines) + "\n"
    a, b = run(G051_EX1), run(incremental)
    x = y = 0.0
    points = []
    for dx, dy in G051_EX2_STEPS:
        x, y = round(x + dx, 3), round(y + dy, 3)
        points.append((x, y))
    assert [tuple(round(c, 6) for c in p[:2]) for p in a.end] == points
    assert all(close(p, q, 1e-12) for p, q in zip(a.end, b.end, strict=True))
    assert math.isclose(sum(a.length), 0.0254, abs_tol=2e-4)
    assert a.smoothing_tolerance_mm.tolist() == [0.01] * 11


def test_e9_g05_1_pauses_after_g43_and_in_g61():
    """§G05.1 examples 3 and 4 (their ``:`` lines are elisions, left out): after ``G43 H3`` the next G01
    is not smoothed and the one after it is again ("restart path smoothing"); G61 stops smoothing and
    G64 restarts it. E0.1 then E0.05 (mm)."""
    ex3 = "G5.1 Q1 E0.1\nG91 G01 F2000\nX -0.005\nG43 H3\nY -0.005\nX -0.005\nM30\n"
    tp = run(ex3)
    assert tp.smoothing_tolerance_mm.tolist() == [0.1, 0.0, 0.1]
    ex4 = ("G5.1 Q1 E0.05\nG90 G01 F2000\nX-0.005 Y0.\nX-0.1 Y-0.01\nG61\nX-0.1 Y-0.02\nX0.005 Y0.\nG64\n"
           "X0.005 Y0.01\nM30\n")  # fmt: skip
    tp = run(ex4)
    assert tp.smoothing_tolerance_mm.tolist() == [0.05, 0.05, 0.0, 0.0, 0.05]


def test_e10_nurbs_quadratic_bezier():
    """§G06.2 example: order P3 with knots 0 0 0 1 1 1 and control points (0,0,0), (0,5,0), (5,5,0) of
    weight 1 is the quadratic Bézier x = 5u², y = 10u - 5u²: it starts at the origin heading +Y, passes
    (1.25, 3.75) at u = 0.5 and ends at (5, 5) heading +X. Its length, ∫|C'(u)|du with C' = (10u, 10 -
    10u), is 8.116 mm (0.097 s at F5000)."""
    text = ("N001 G0 X0.0 Y0.0 Z0.0\nN002 G05 P10000//Start high speed & high precision interpolation\n"
            "N003 G06.2 P3 K0.0 X0.0 Y0.0 Z0.0 R1.0 F5000.\nN004 K0.0 X0.0 Y5.0 Z0.0 R1.0\n"
            "N005 K0.0 X5.0 Y5.0 Z0.0 R1.0\nN006 K1.0\nN007 K1.0\nN008 K1.0\nN009 G05 P0\n")  # fmt: skip
    tp = run(text)
    assert len(tp) == 1 and tp.kind[0] == 4 and tp.feed[0] == 5000.0
    n = 200000
    u = [(k + 0.5) / n for k in range(n)]
    length = sum(math.hypot(10 * t, 10 - 10 * t) for t in u) / n
    assert math.isclose(tp.length[0], length, abs_tol=1e-6)
    assert math.isclose(length, 8.116, abs_tol=5e-4)
    point, tangent, _ = tp.evaluate([0.0, tp.length[0]])
    assert close(point[0], (0, 0, 0)) and close(point[1], (5, 5, 0))
    assert close(tangent[0], (0, 1, 0)) and close(tangent[1], (1, 0, 0))
    s = [k * tp.length[0] / 4000 for k in range(4001)]
    points, _, _ = tp.evaluate(s)
    assert min(math.dist(p[:2], (1.25, 3.75)) for p in points) < 2e-3


# ---------------------------------------------------------------------- §G15/G16
POLAR_HEAD = ("N001 T1 S1000 M03 ;\nN002 G17 G90 G16 ;\nN003 G99 G81 Z-12.0 R2.0 F600 K0 ;\n"
              "N004 X100.0 Y90.0 ;\n")


def holes(text: str, bottom: float) -> list[tuple[float, float]]:
    """The XY of every feed move that ends at the hole bottom."""
    return [(round(r[1][0], 3) + 0.0, round(r[1][1], 3) + 0.0) for r in path(text)
            if r[0] == "F" and math.isclose(r[1][2], bottom)]  # fmt: skip


def test_e11_polar_drilling_absolute():
    """§G15/G16 example 1: radius 100 at 90°, 210°, 330° (angles counter-clockwise from +X, the reading of
    the manual's own G135/G136; its G16 text says "+ for CW"): holes at (0, 100), (-86.603, -50), (86.603,
    -50), drilled to Z-12 from R2, back to R (G99). The K0 block only stores the cycle."""
    text = POLAR_HEAD + "N005 Y210.0 ;\nN006 Y330.0 ;\nN007 G15 G80 M05 ;\nN008 M30 ;\n"
    expected = [polar_point(100, a) for a in (90, 210, 330)]
    assert all(close(h, e) for h, e in zip(holes(text, -12.0), expected, strict=True))
    assert path(text)[:4] == [("R", (0.0, 100.0, 0.0)), ("R", (0.0, 100.0, 2.0)),
                              ("F", (0.0, 100.0, -12.0), 600.0), ("R", (0.0, 100.0, 2.0))]


def test_e12_polar_drilling_incremental_drills_four_holes():
    """§G15/G16 example 2: ``G91 Y120.0 K2`` adds 120° twice (210°, 330°) and ``Y120.0`` once more: 450° =
    90°, so the first hole is drilled again — four holes. The comments expect three (the K2 already
    covers the third); the code is the oracle."""
    text = POLAR_HEAD + "N005 G91 Y120.0 K2 ;\nN006 Y120.0 ;\nN007 G15 G80 M05 ;\nN008 M30 ;\n"
    expected = [polar_point(100, a) for a in (90, 210, 330, 450)]
    found = holes(text, -12.0)
    assert len(found) == 4 and all(close(h, e) for h, e in zip(found, expected, strict=True))


# ---------------------------------------------------------------------- §G28-§G31, §G33
def _machine(references: dict[int, tuple[float, float, float]]) -> MachineConfig:
    axes = tuple(AxisConfig(**{f"reference_{n}_mm": v[a] for n, v in references.items()}) for a in range(3))
    return MachineConfig(name="syntec-test", axes=axes)  # type: ignore[arg-type]


def test_e13_g28_g29_via_the_mid_point():
    """§G28/§G29 examples (the start A comes from a lost figure: (10, 10) here). Absolute: G28 X20 Y30 goes
    A → mid-point (20, 30) → reference point (machine zero); G29 X40 Y0 goes back through (20, 30) to (40,
    0). The comment's "mid-point(20,40)" contradicts Y30.0; the code is the oracle. Incremental: G28 X20
    Y40 makes the mid-point A + (20, 40) = (30, 50); G29 X40 Y-40 ends at mid-point + (40, -40) = (70,
    10)."""
    absolute = "G00 X10. Y10.\nN001 G90 G28 X20.0 Y30.0;\nN002 M06;\nN003 G29 X40.0 Y0.0;\n"
    assert path(absolute) == [("R", (10.0, 10.0, 0.0)), ("R", (20.0, 30.0, 0.0)), ("R", (0.0, 0.0, 0.0)),
                              ("R", (20.0, 30.0, 0.0)), ("R", (40.0, 0.0, 0.0))]  # fmt: skip
    incremental = "G00 X10. Y10.\nN001 G91 G28 X20.0 Y40.0;\nN002 M06;\nN003 G29 X40.0 Y-40.0;\n"
    assert path(incremental) == [("R", (10.0, 10.0, 0.0)), ("R", (30.0, 50.0, 0.0)), ("R", (0.0, 0.0, 0.0)),
                                 ("R", (30.0, 50.0, 0.0)), ("R", (70.0, 10.0, 0.0))]  # fmt: skip


def test_e14_g30_second_and_third_reference_points():
    """§G30 example: from A (60, 10), ``G30 P2 X75.0 Y25.0`` goes A → B (75, 25) → the 2nd reference point,
    ``G30 P3 X15.0 Y10.0`` → C (15, 10) → the 3rd; only X and Y move (the commanded axes). Reference
    points from the machine (Pr2801-2860): here 2nd (-100, -50, 0), 3rd (-200, -50, 0)."""
    machine = _machine({2: (-100.0, -50.0, 0.0), 3: (-200.0, -50.0, 0.0)})
    text = "G00 X60. Y10.\nG30 P2 X75.0 Y25.0 ;\nG00 X60. Y10.\nG30 P3 X15.0 Y10.0 ;\n"
    assert path(text, machine=machine) == [
        ("R", (60.0, 10.0, 0.0)), ("R", (75.0, 25.0, 0.0)), ("R", (-100.0, -50.0, 0.0)),
        ("R", (60.0, 10.0, 0.0)), ("R", (15.0, 10.0, 0.0)), ("R", (-200.0, -50.0, 0.0))]  # fmt: skip


def test_e15_g31_skip_then_the_next_block_from_the_contact_point():
    """§G31 examples 1-3, with the obstacle at X60 / X150 / X80 (the manual's figures are lost). Example 1
    (G91): the skip stops at (60, 0), and ``Y100.0`` is incremental from there: (60, 100). Example 2 (G90):
    stops at (150, 0), then ``X200.0 Y100.0`` absolute. Example 3: stops at (80, 0), then (130, 70)."""
    ex1 = "N001 G31 G91 X100.0 F100;\nN002 Y100.0;\n"
    assert [r[1][:2] for r in path(ex1, skip_signal={"X": 60.0})] == [(60.0, 0.0), (60.0, 100.0)]
    ex2 = "N001 G31 G90 X200.0 F100;\nN002 X200.0 Y100.0;\n"
    assert [r[1][:2] for r in path(ex2, skip_signal={"X": 150.0})] == [(150.0, 0.0), (200.0, 100.0)]
    ex3 = "N001 G31 G90 X100.0 F1000;\nN002 X130.0 Y70.0;\n"
    assert [r[1][:2] for r in path(ex3, skip_signal={"X": 80.0})] == [(80.0, 0.0), (130.0, 70.0)]


def test_e16_g33_thread_lead():
    """§G33 example: ``G33 Z10.0 F1.5`` is a 1.5 mm lead to Z10: at S500 the feed is 1.5 × 500 = 750
    mm/min, with the override fixed (spindle and axis synchronised)."""
    rows = records("S500 M03\nG33 Z10.0 F1.5 ;\n")
    assert rows[0]["end"] == [0.0, 0.0, 10.0] and rows[0]["feed"] == 750.0
    assert rows[0]["modes"] == ["override_locked"]


# ---------------------------------------------------------------------- §G37, §G37.1
G37_PROGRAM = """G30 P2 X75.0 Y25.0; // return to reference point 2
M06 T1; // change to T1
H1; // define the tool length compensation H1
G37 Z-150; // move Z axis to -150.
G53 Z0.
M06 T2;
H2;
G37 Z-150;
G53 Z0.
M06 T3;
H3;
G37 P2 Z-200.; // return to reference point 2, move Z to -200.
"""


def test_e17_g37_program_measures_three_tools():
    """§G37 program form. ``Z-150`` has no decimal point, so by the manual's number rule it is -0.150 mm
    (the comment says "-150."; the code is the oracle, and ``Z-200.`` is -200 mm). G37 leaves the tool where
    the probe fired, and the next G37 must start above its starting point (MAR-333): the program relies on
    the tool change M06 taking Z up, which the simulation does not move (the changer is the machine
    builder's), so the test writes that move out as ``G53 Z0.`` before each M06. With a measuring distance
    R of 0.1 mm (Pr4055) and an over-travel D of 1 mm (Pr4056) each measurement rapids to Z + R, then
    probes down: H1's probe fires at Z-0.12 (offset +0.03), H2's at -0.15 (no change), H3's at -200.5
    (offset -0.5). The reference point 2 is the machine zero (default preset)."""
    settings = {"signal_at": {1: -0.12, 2: -0.15, 3: -200.5}, "decel_mm": 0.1, "band_mm": 1.0}
    assert path(G37_PROGRAM, tool_measurement=settings) == [
        ("R", (75.0, 25.0, 0.0)), ("R", (0.0, 0.0, 0.0)),  # G30 P2: mid-point, reference point 2
        ("R", (0.0, 0.0, -0.05)), ("F", (0.0, 0.0, -0.12), 1000.0),  # H1: rapid to Z+R, probe
        ("R", (0.0, 0.0, 0.0)),  # G53 Z0.
        ("R", (0.0, 0.0, -0.05)), ("F", (0.0, 0.0, -0.15), 1000.0),  # H2
        ("R", (0.0, 0.0, 0.0)),
        ("R", (0.0, 0.0, -199.9)), ("F", (0.0, 0.0, -200.5), 1000.0)]  # H3 (P2: already there)  # fmt: skip
    assert error(G37_PROGRAM.replace("G53 Z0.\nM06 T2", "M06 T2"), tool_measurement=settings).alarm == 333
    assert error(G37_PROGRAM.replace("H1;", "")).alarm == 334  # MAR-334: no H before G37
    assert error("H1;\nG37 R5.;\n").alarm == 330  # MAR-330: no Z


def test_e18_g37_1_program_double_touch():
    """§G37.1 program form (Z in machine coordinates): rapid to Z + R, probe at F toward Z, 1 mm back up at
    rapid, second touch at F50, then Z to the machine zero (no Q). H1's probe fires at -0.12: -0.05 →
    -0.12 → -0.11 (but no higher than the start -0.05) → -0.12 at F50 → 0."""
    settings = {"signal_at": {1: -0.12}, "decel_mm": 0.1}
    text = "G30 P2 X75.0 Y25.0;\nM06 T1;\nH1;\nG37.1 Z-150;\n"
    assert path(text, tool_measurement=settings) == [
        ("R", (75.0, 25.0, 0.0)), ("R", (0.0, 0.0, 0.0)), ("R", (0.0, 0.0, -0.05)),
        ("F", (0.0, 0.0, -0.12), 1000.0), ("R", (0.0, 0.0, -0.05)), ("F", (0.0, 0.0, -0.12), 50.0),
        ("R", (0.0, 0.0, 0.0))]  # fmt: skip
    assert error(text.replace("H1;\n", "")).alarm == 334


# ---------------------------------------------------------------------- §G40-§G43
LOBED_POCKET = """N001 T1 S1000 M03 ; //tool NO.1(diameter 10mm), spindle 1000rpm (CW)
N002 G00 X0.0 Y0.0 Z10.0 ;
N003 M08 ;
N004 G90 G01 Z-10.0 F600 ;
N005 G42 Y24.0 D01 ; //cutter compensation left, program zero point→A
N006 G03 X9.0 Y30.0 R10.0 ; //A→B
N007 G02 X30.0 Y9.0 R15.0 ;
N008 G03 X30.0 Y-9.0 R10.0 ;
N009 G02 X9.0 Y-30.0 R15.0 ;
N010 G03 X-9.0 Y-30.0 R10.0 ;
N011 G02 X-30.0 Y-9.0 R15.0 ;
N012 G03 X-30.0 Y9.0 R10.0 ;
N013 G02 X-9.0 Y30.0 R15.0 ;
N014 G03 X0.0 Y24.0 R10.0 ; //M→A
N015 G00 Z10.0 ;
N016 G40 X0.0 Y0.0 ;
N017 M09 ;
N018 M05 ;
N019 M30 ;
"""


def test_e19_lobed_pocket_with_g42():
    """§G40/G41/G42 example (tool Ø10, D01 = 5). The comment of N005 says "left"; the code says G42 (right),
    and the code is the oracle. The contour runs clockwise about the origin, so G42 keeps the tool inside:
    every compensated arc is concentric with its programmed arc, the G03 arcs (R10, CCW, the tool on their
    outside) at radius 15 and the G02 lobes (R15, CW, the tool on their inside) at radius 10. The
    programmed centres, from the chords: lobes at (±18, ±18), concave arcs at (±34.359, 0) and (0, -34.359),
    and the top one split at A (0, 24) into arcs about (∓0.166, 33.999)."""
    points = [(0, 24), (9, 30), (30, 9), (30, -9), (9, -30), (-9, -30), (-30, -9), (-30, 9), (-9, 30),
              (0, 24)]
    radii = [10, 15, 10, 15, 10, 15, 10, 15, 10]
    arcs = [r for r in path(LOBED_POCKET, tool_offsets={"D": {1: 5.0}}) if r[0] == "A"]
    assert len(arcs) == 9
    for k, arc in enumerate(arcs):
        ccw = k % 2 == 0
        centre = r_centre(points[k], points[k + 1], radii[k], ccw)
        assert close(arc[2][:2], centre), (k, arc, centre)
        assert math.isclose(arc[3], radii[k] + (5 if ccw else -5), abs_tol=1e-3)
        assert (arc[4] > 0) == ccw
    assert close(r_centre((9, 30), (30, 9), 15, False), (18, 18))
    assert close(r_centre((30, 9), (30, -9), 10, True), (34.359, 0))


OUTLINE = """T1 S1000 M03 ; //use tool NO.1(diameter 20mm), spindle 1000rpm(CW)
G42 D01 ; //tool radius compensation right(D01=10)
G00 X10.0 Y5.0 Z15.0 ; //positioning above A point
G43 H01 ; //tool length compensation positive(H01=-10)
G01 Z-10.0 ;
X110.0 ; //A→B
Y85.0 ;
X90.0 Y105.0 ;
X50.0 ;
G02 X10.0 Y65.0 R40.0 ;
G01 Y5.0 ;
G00 Z15.0 ;
G40 G49 ;
M05 ;
M30 ;
"""


def test_e20_outline_with_g42_and_g43():
    """§G43/G44/G49 example (D01 = 10, H01 = -10). No F anywhere: the default 1000 mm/min. The contour A (10,
    5) → B (110, 5) → C (110, 85) → D (90, 105) → E (50, 105) → F (10, 65) (G02 R40 about (10, 105), the
    short way) → A runs counter-clockwise, so G42 keeps the tool outside, 10 mm off every element: the
    edges at y = -5, x = 120, on the 45° edge's parallel, y = 115, the arc at radius 40 - 10 = 30 about
    (10, 105), x = 0. Outer corners meet on the extended offsets: B at (120, -5), C at (120, 89.142)
    (x = 120 on the parallel through C + 10·(0.707, 0.707)), D at (94.142, 115). G43 with H01 = -10 puts
    Z-10 at -20 and Z15 at 5."""
    rows = path(OUTLINE, tool_offsets={"D": {1: 10.0}, "H": {1: -10.0}})
    ends = [r[1] for r in rows if r[0] in "FA"]
    for corner in ((120, -5), (120, 89.142), (94.142, 115)):
        assert any(close(e[:2], corner) and e[2] == -20.0 for e in ends), corner
    arc = next(r for r in rows if r[0] == "A")
    assert close(arc[2][:2], (10, 105)) and math.isclose(arc[3], 30.0, abs_tol=1e-6) and arc[4] < 0
    assert {r[2] for r in rows if r[0] == "F"} == {1000.0}
    assert any(r[0] == "R" and r[1][2] == 5.0 for r in rows)  # G00 Z15 with the -10 offset


# ---------------------------------------------------------------------- §G51/G50, §G51.1/G50.1, §G52, §G53
def test_e21_scaling_by_half_about_125_90():
    """§G51/G50 example: p' = (125, 90) + 0.5·(p - (125, 90)) from N003 to N009: (50, 70) → (87.5, 80),
    (100, 150) → (112.5, 120), the G03 arc about (100 + 25, 150) of radius 25 → about (125, 120) of radius
    12.5, to (150, 150) → (137.5, 120), sweeping 180° counter-clockwise (through (125, 107.5)); (200, 70)
    → (162.5, 80); (200, 50) → (162.5, 70); (50, 50) → (87.5, 70); G00 (0, 0) → (62.5, 45)."""
    text = ("N001 G00 X50.0 Y50.0 ;\nN002 G51 X125.0 Y90.0 P0.5 ;\nN003 G01 Y70.0 F1000 ;\n"
            "N004 X100.0 Y150.0 ;\nN005 G03 X150.0 I25.0 ;\nN006 G01 X200.0 Y70.0 ;\nN007 Y50.0 ;\n"
            "N008 X50.0 ;\nN009 G00 X0.0 Y0.0 ;\nN010 G50 ;\nN011 M30 ;\n")  # fmt: skip
    assert path(text) == [
        ("R", (50.0, 50.0, 0.0)), ("F", (87.5, 80.0, 0.0), 1000.0), ("F", (112.5, 120.0, 0.0), 1000.0),
        ("A", (137.5, 120.0, 0.0), (125.0, 120.0, 0.0), 12.5, 180.0), ("F", (162.5, 80.0, 0.0), 1000.0),
        ("F", (162.5, 70.0, 0.0), 1000.0), ("F", (87.5, 70.0, 0.0), 1000.0), ("R", (62.5, 45.0, 0.0))]


CROSS_POCKET = """N001 T1 S1000 M03 ;
N002 G54 X0.0 Y0.0 Z0.0 ;
N003 G00 X90.0 Y15.0 Z10.0 ;
N004 G43 H01 ;
N005 G99 G81 Z-15.0 R2.0 F1000 ;
N006 X110.0 ;
N007 X100.0 Y65.0 ;
N008 G80 ;
N009 M05 ;
N010 G28 X0.0 Y0.0 Z10.0 ;
N011 T2 M06 S1000 M03 ;
N012 G52 X30.0 Y30.0 Z0.0 ; //specify local coordinate zero point … X40.0,Y40.0,Z0.0
N013 G00 X0.0 Y0.0 Z10.0;
N014 G01 Z-12.0;
N015 G17 G41 D02 ;
N016 G91 X20.0 ;
N017 Y10.0 ;
N018 X-10.0 ;
N019 Y10.0 ;
N020 X-20.0 ;
N021 Y-10.0 ;
N022 X-10.0 ;
N023 Y-20.0 ;
N024 X10.0 ;
N025 Y-10.0 ;
N026 X20.0 ;
N027 Y10.0 ;
N028 X10.0 ;
N029 Y10.0 ;
N030 G90 G00 Z10.0 ;
N031 G52 X0.0 Y0.0 Z0.0 ;
N032 G40 M05 ;
N033 M30 ;
"""


def test_e22_g52_cross_pocket():
    """§G52 example (H01 = 0, D02 = 5). Three holes at (90, 15), (110, 15), (100, 65), Z-15 from R2 (G99),
    then the local origin at (30, 30) (the comment says 40, 40; the code is the oracle). The G91 moves trace
    a cross with 10 mm arms about the local origin, counter-clockwise, G41: the tool (Ø10) runs 5 mm
    inside each edge. Offsetting every edge by 5 to its left and meeting the neighbours: (15, 5) [the
    (20, 10)→(10, 10) edge shrinks to nothing: the arm is exactly one tool wide], (5, 5), (5, 15), (-5,
    15), (-5, 5), (-15, 5), (-15, -5), (-5, -5), (-5, -15), (5, -15), (5, -5), (15, -5), and at the end of
    the last block, with G40 in a block without a move, (15, 0) — all + (30, 30). No F after the cycle's
    F1000: it stays modal."""
    assert holes(CROSS_POCKET, -15.0) == [(90.0, 15.0), (110.0, 15.0), (100.0, 65.0)]
    local = [(15, 5), (5, 5), (5, 15), (-5, 15), (-5, 5), (-15, 5), (-15, -5), (-5, -5), (-5, -15), (5, -15),
             (5, -5), (15, -5), (15, 0)]  # fmt: skip
    rows = path(CROSS_POCKET, tool_offsets={"D": {2: 5.0}})
    contour = [r for r in rows if r[0] == "F" and r[1][2] == -12.0][1:]  # after the plunge to Z-12
    assert [r[1][:2] for r in contour] == [(x + 30.0, y + 30.0) for x, y in local]
    assert {r[2] for r in contour} == {1000.0}


def test_e23_g53_machine_positioning_is_one_shot():
    """§G53 example: G92 X-200 Y-100 at the machine origin shifts the work systems by (200, 100) (the Fanuc
    0M rule: the G92 shift applies to G54-G59 and stays when one is selected — the example's N001 "specify
    to basic coordinate system" would do nothing if G54 dropped it); N002 G54 X100 Y200 is machine
    (300, 300); G53 X300 Y100 is machine (300, 100) for its block only; N004 X300 Y0 is G54 again, shifted
    (machine (500, 100)); G52 X300 Y200 then X0 Y0 is machine (500, 300). The motion mode is the power-on
    G00."""
    text = ("N001 G92 X-200.0 Y-100.0 ;\nN002 G54 G90 X100.0 Y200.0 ;\nN003 G53 X300.0 Y100.0 ;\n"
            "N004 X300.0 Y0 ;\nN005 G52 X300.0 Y200.0 ;\nN006 X0.0 Y0.0 ;\n")  # fmt: skip
    assert [r[1][:2] for r in path(text)] == [(300.0, 300.0), (300.0, 100.0), (500.0, 100.0), (500.0, 300.0)]


MIRROR_EX1 = """N001 T1 S1000 M03 ;
N002 M98 H100 ;
N003 G51.1 X60.0 ;
N004 M98 H100 ;
N005 G50.1 ;
N006 G51.1 Y55.0 ;
N007 M98 H100 ;
N008 G50.1 ;
N009 M05 ;
N010 M30 ;
N100 ; //sub-program list
G00 X60.0 Y55.0 ;
G01 Y75.0 ;
X80.0 ;
X120.0 ;
Y105.0 ;
X80.0 Y95.0 ;
Y75.0 ;
M99 ;
"""


def test_e24_mirror_example_1():
    """§G51.1/G50.1 example 1: the N100 section (after M30, called by ``M98 H100``) three times. No F: the
    default 1000 mm/min. Pass 1 as programmed; pass 2 mirrored about X = 60 (x' = 120 - x); pass 3 about
    Y = 55 (y' = 110 - y)."""
    shape = [(60, 55), (60, 75), (80, 75), (120, 75), (120, 105), (80, 95), (80, 75)]
    expected = shape + [(120 - x, y) for x, y in shape] + [(x, 110 - y) for x, y in shape]
    rows = path(MIRROR_EX1)
    assert [r[1][:2] for r in rows] == [(float(x), float(y)) for x, y in expected]
    assert {r[2] for r in rows if r[0] == "F"} == {1000.0}


FLOWER = """N001 T1 S1000 M03 ;
N002 G41 D01 ;
N003 M98 H100 ;
N004 G51.1 X0.0 ;
N005 M98 H100 ;
N006 G50.1 ;
N007 G51.1 X0.0 Y0.0 ;
N008 M98 H100 ;
N009 G50.1 ;
N010 G51.1 Y0.0 ;
N011 M98 H100 ;
N012 G50.1 ;
N013 G40 ;
N014 M05 ;
N015 M30 ;
N100 ; sub-program list
G00 X58.0 Y0.0 Z10.0 ;
G01 Z-10.0 ;
G03 X49.36 Y7.9744 R8.0 ;
G03 X40.5415 Y29.2641 R50.0 ;
G03 X29.2641 Y40.5415 R8.0 ;
G03 X7.9744 Y49.36 R50.0 ;
G03 X0.0 Y58.0 R8.0 ;
G00 Z10.0 ;
M99 ;
"""


def test_e25_mirror_example_2_flower_trough():
    """§G51.1/G50.1 example 2. ``N100 ; sub-program list`` has no ``//`` (a conversion slip): written with
    one. The quadrant: R8 tips about (50, 0), (34.45, 34.45), (0, 50) joined by R50 arcs about the origin,
    all G03. Mirroring X (pass 2) or Y (pass 4) alone reverses the arcs (G02), mirroring both (pass 3)
    does not. With the manual's D01 = 5 the type-C start-up into the first R8 tip (a 90° inner corner) has
    no intersection of the offset paths (offset line y = 5, offset circle of radius 3): refused
    (``comp-no-intersection``); the geometry is checked with D01 = 0."""
    text = FLOWER.replace("N100 ; sub-program list", "N100 // sub-program list")
    assert error(text, tool_offsets={"D": {1: 5.0}}).code == "comp-no-intersection"
    arcs = [r for r in path(text) if r[0] == "A"]
    assert len(arcs) == 20
    tips = [(50.0, 0.0), (34.454, 34.454), (0.0, 50.0)]
    signs = [(1, 1, 1), (-1, 1, -1), (-1, -1, 1), (1, -1, -1)]  # (x, y, direction) per pass
    for k, (sx, sy, direction) in enumerate(signs):
        quadrant = arcs[5 * k:5 * k + 5]
        centres = [tips[0], (0.0, 0.0), tips[1], (0.0, 0.0), tips[2]]
        radii = [8.0, 50.0, 8.0, 50.0, 8.0]
        for arc, centre, radius in zip(quadrant, centres, radii, strict=True):
            assert close(arc[2][:2], (sx * centre[0], sy * centre[1]), 2e-3), (k, arc)
            assert math.isclose(arc[3], radius, abs_tol=2e-3)
            assert (arc[4] > 0) == (direction > 0)


# ---------------------------------------------------------------------- §G65, §G66/G67
def test_e26_g65_and_g66_calls():
    """§G65: ``G65 P10 L20 X10.0 Y10.0`` runs O0010 twenty times with X = 10 and Y = 10 set into it (here
    #24/#25, the Fanuc argument map: the manual names none). O0010 moves X by #24 in G91: 20 moves of 10
    mm. §G66/G67: in G91, ``G66 P10 L2 X10.0 Y10.0`` arms the call; ``X20.0`` moves, then O0010 runs twice;
    ``Y20.0`` the same; G67 ends it: X 20, 30, 40, then Y 20, X 50, 60."""
    sub = "O0010\nG91 G01 X#24 F100\nM99\n"
    rows = path("G65 P10 L20 X10.0 Y10.0\nM30\n" + sub)
    assert [r[1][0] for r in rows] == [10.0 * k for k in range(1, 21)]
    rows = path("G91\nG66 P10 L2 X10.0 Y10.0\nX20.0\nY20.0\nG67\nX5.\nM30\n" + sub)
    assert [r[1][:2] for r in rows] == [(20.0, 0.0), (30.0, 0.0), (40.0, 0.0), (40.0, 20.0), (50.0, 20.0),
                                        (60.0, 20.0), (65.0, 20.0)]  # fmt: skip


# ---------------------------------------------------------------------- §G68/G69
G68_EX1 = """G54 X0 Y0 F3000.;
G16; // start polar coordinates
G90 G00 X50. Y9.207; // positioning to starting point
M98 H100; // first process
G68 X0 Y0 R90.; // coordinate rotates 90°
M98 H100; // second process
G68 X0 Y0 R180.; // coordinate rotates 180°
M98 H100; // third process
G68 X0 Y0 R270.; // coordinate rotates 270°
M98 H100; // fourth process
G69; // coordinate rotation cancel
G15; // polar coordinate cancel
M02; // main program end
N100 // orbit sub-program start
G90 G01 X50. Y9.207;
G03 X50. Y80.793 R50.;
G03 X50. Y99.207 R8.;
M99; // orbit sub-program return
"""


def test_e27_g68_rotated_contour_of_four_arcs():
    """§G68/G69 example 1, with two typos repaired: ``R8.`` on the G00/G01 blocks (a radius word on a
    line, refused) and the double point of ``Y80.793.`` (refused). In polar input, 50∠9.207° = (49.356,
    8.0); the R50 arc to 50∠80.793° (71.586°, CCW about the origin) and the R8 arc to 50∠99.207°: its
    chord 100·sin 9.207° = 16.00018 mm is 0.18 µm longer than 2R, inside the arc tolerance, so a half
    circle about the chord's middle 49.356∠90°. Each G68 replaces the rotation: the four passes close one
    contour of 4 R50 arcs and 4 bumps about 49.356∠0°, 90°, 180°, 270°: 350.41 mm, 7.01 s at F3000."""
    assert error(G68_EX1.replace("X50. Y9.207;", "X50. Y9.207 R8.;", 1)).code == "unused-word"
    assert error(G68_EX1.replace("Y80.793 ", "Y80.793. ")).code == "bad-number"
    tp = run(G68_EX1)
    arcs = [r for r in path(G68_EX1) if r[0] == "A"]
    assert len(arcs) == 8
    for k in range(4):
        big, bump = arcs[2 * k], arcs[2 * k + 1]
        assert close(big[2][:2], (0, 0)) and big[3] == 50.0 and math.isclose(big[4], 71.586, abs_tol=1e-3)
        assert close(bump[2][:2], polar_point(49.356, 90 * (k + 1)), 2e-3) and math.isclose(bump[4], 180.0)
    assert close(tp.end[-1][:2], tp.start[1][:2])  # closed
    cut = sum(tp.length[i] for i in range(len(tp)) if tp.kind[i] == 2)
    expected = 4 * 50 * math.radians(2 * (90 - 9.207) - 90) + 4 * math.pi * 50 * math.sin(math.radians(9.207))
    assert math.isclose(cut, expected, abs_tol=1e-3) and math.isclose(cut, 350.41, abs_tol=0.01)
    assert math.isclose(cut / 3000 * 60, 7.01, abs_tol=0.01)


G68_EX2 = """G54 X0 Y0 F3000.;
G16;
G90 G00 X50. Y9.207;
M98 H100;
G68 X0 Y0 R45.;
M98 H100;
G68 X0 Y0 R90.;
M98 H100;
G68 X0 Y0 R135.;
M98 H100;
G68 X0 Y0 R180.;
M98 H100;
G68 X0 Y0 R225.;
M98 H100;
G68 X0 Y0 R270.;
M98 H100;
G68 X0 Y0 R315.;
M98 H100;
G69;
G15;
G00 X-80. Y0.
M98 H200; // process first “flower”
G51.1 Y-40.; // symmetry axis Y-40.
M98 H200; // process second “flower”
G50.1; // mirror image cancel
G90 G81 Z-20. R2. F1000. K0;
G134 X0 Y0 I75. J30. K6; // circumference hole cycle
G137.1 X60. Y-60. I20. J-20. P3 K3; // chess type hole cycle
G80;
M02;
N100 // orbit sub-program
G90 G01 X50. Y9.207;
G03 X50. Y35.793 R50.;
G03 X50. Y54.207 R8.;
M99;
N200 // sub-program start (flower)
G90 G00 X-70. Y10.;
G91 G03 X-20. R10.;
G03 Y-20. R10.;
G03 X20. R10.;
G03 Y20. R10.;
M99; // sub-program return (flower)
"""


def test_e28_g68_eight_petals_two_flowers_and_hole_patterns():
    """§G68/G69 example 2 (the stray ``R8.`` and wrapped comment tails repaired as in E27). Eight passes:
    8 R50 arcs of 2·(45 - 9.207)° - … = 26.586° and 8 R8 bumps at 45°·k, 386.67 mm. N200 from (-70, 10)
    in G91: four R10 half circles about (-80, 10), (-90, 0), (-80, -10), (-70, 0) — a flower about (-80,
    0). ``G51.1 Y-40.`` is given while N200's G91 is still in force (modal state leaks out of a
    subprogram) and is absolute: the second flower about (-80, -80), its arcs reversed. The manual writes
    ``G50;`` for the mirror cancel: G50 is the scaling cancel, which would leave the mirror on and put the
    holes below Y-100, outside the screenshot's graph range Y (-100, 75); the test reads G50.1. Holes:
    G134 r = 75 at 30° + 60°k; G137.1 from (60, -60), 3 × 3, 20 apart in X and -20 in Y, row by row."""
    rows = path(G68_EX2)
    arcs = [r for r in rows if r[0] == "A"]
    petals, flowers = arcs[:16], arcs[16:]
    assert [round(a[4], 3) for a in petals[0::2]] == [26.586] * 8
    assert all(close(b[2][:2], polar_point(49.356, 45 * (k + 1)), 2e-3) for k, b in enumerate(petals[1::2]))
    cut = sum(math.radians(abs(a[4])) * a[3] for a in petals)
    assert math.isclose(cut, 386.67, abs_tol=0.01)
    first = [(-80, 10), (-90, 0), (-80, -10), (-70, 0)]
    assert [a[2][:2] for a in flowers[:4]] == [(float(x), float(y)) for x, y in first]
    assert [a[2][:2] for a in flowers[4:]] == [(float(x), float(-80 - y)) for x, y in first]
    assert all(a[4] == 180.0 for a in flowers[:4]) and all(a[4] == -180.0 for a in flowers[4:])
    bolt = [polar_point(75, 30 + 60 * k) for k in range(6)]
    grid = [(60, -60), (80, -60), (100, -60), (100, -80), (80, -80), (60, -80), (60, -100), (80, -100),
            (100, -100)]  # fmt: skip
    found = holes(G68_EX2, -20.0)
    assert len(found) == 15
    assert all(close(h, e) for h, e in zip(found, bolt + grid, strict=True))
    as_printed = holes(G68_EX2.replace("G50.1; // mirror image cancel", "G50;"), -20.0)
    assert close(as_printed[0], (bolt[0][0], -80 - bolt[0][1]))  # the mirror stays on


# ---------------------------------------------------------------------- §G73-§G89 (the standard program)
def standard(code_block: str, *, fifth: bool, spindle: str = "M03") -> str:
    """The manual's standard cycle program (§G73-§G89 examples): F1000 S500, initial level Z10, G99, holes
    (5, 5), (15, 5), (15, 15), G98 (5, 15) and for G73/G74/G76/G81 a fifth at (10, 10) to Z-20."""
    text = (f"F1000. S500;\n{spindle};\nG90;\nG00 X0. Y0. Z10.; // positioning to initial point\nG17;\n"
            f"G90 G99;\n{code_block}\nX15.; // hole 2\nY15.; // hole 3\nG98 X5.; // hole 4\n")
    if fifth:
        text += "X10. Y10. Z-20.; // hole 5\n"
    return text + "G80;\nM05;\nM02;\n"


HOLES = [(5.0, 5.0), (15.0, 5.0), (15.0, 15.0), (5.0, 15.0), (10.0, 10.0)]


def expected_cycle(hole_steps, *, fifth: bool) -> list[tuple]:
    """The path the manual's step lists give: from (0, 0, 10), for each hole a rapid in XY at the current
    level, a rapid to R (-5) unless already there, then ``hole_steps(x, y, bottom, back)`` (``back``: the
    return level, R for holes 1-3 (G99), the initial level 10 from hole 4 on (G98))."""
    rows: list[tuple] = [("R", (0.0, 0.0, 10.0))]
    level = 10.0
    for k, (x, y) in enumerate(HOLES[:5 if fifth else 4]):
        rows.append(("R", (x, y, level)))
        if level != -5.0:
            rows.append(("R", (x, y, -5.0)))
        back = -5.0 if k < 3 else 10.0
        steps = hole_steps(x, y, -20.0 if k == 4 else -10.0, back)
        rows.extend(steps)
        level = next(s[1][2] for s in reversed(rows) if s[0] in "RF")
    return rows


def test_e29_g73_high_speed_peck():
    """§G73 (Q2, d = Pr4002 = 0.5 mm): feed 2 deeper, rapid up d, feed to 2 below the last depth, … the last
    peck clipped at Z: -7, up to -6.5, -9, up to -8.5, -10; hole 5 to -20 by nine pecks; rapid out."""
    def steps(x, y, bottom, back):
        out, depth = [], -5.0
        while True:
            depth = max(depth - 2.0, bottom)
            out.append(("F", (x, y, depth), 1000.0))
            if depth == bottom:
                return [*out, ("R", (x, y, back))]
            out.append(("R", (x, y, depth + 0.5)))
    assert path(standard("G73 X5. Y5. Z-10. R-5. Q2.;", fifth=True)) == expected_cycle(steps, fifth=True)


def test_e30_g74_left_hand_tapping():
    """§G74 (M04, P2. = 2 s): feed to Z, dwell 2 s and reverse, feed back to R, dwell 2 s and reverse, and
    with G98 rapid to the initial level; every tapping feed with the override fixed."""
    def steps(x, y, bottom, back):
        out = [("F", (x, y, bottom), 1000.0), ("D", 2.0), ("F", (x, y, -5.0), 1000.0), ("D", 2.0)]
        return out + ([("R", (x, y, back))] if back != -5.0 else [])
    text = standard("G74 X5. Y5. Z-10. R-5. P2.;", fifth=True, spindle="M04")
    assert path(text) == expected_cycle(steps, fifth=True)
    assert all(r.get("modes") == ["override_locked"] for r in records(text) if r["kind"] == "line")
    tp = run(text)
    lines = [i for i in range(len(tp)) if tp.kind[i] == 1]
    assert [tp.spindle_rpm[i] for i in lines[:2]] == [-500.0, 500.0]  # in CCW (M04), out reversed


def test_e31_g76_fine_boring():
    """§G76 (Q2. shift, P5. = 5 s): feed to Z, dwell 5 s, oriented stop (a 0 s exact stop), shift 2 mm in
    +X (Pr4020 = 0), rapid to the return level, shift back."""
    def steps(x, y, bottom, back):
        return [("F", (x, y, bottom), 1000.0), ("D", 5.0), ("D", 0.0), ("R", (x + 2, y, bottom)),
                ("R", (x + 2, y, back)), ("R", (x, y, back))]  # fmt: skip
    text = standard("G76 X5. Y5. Z-10. R-5. Q2. P5.;", fifth=True)
    assert path(text) == expected_cycle(steps, fifth=True)


def test_e32_g81_drilling():
    """§G81 (the notes' reference case): feed to Z, rapid out. Feed length 4 × 5 + 15 = 35 mm: 2.1 s."""
    def steps(x, y, bottom, back):
        return [("F", (x, y, bottom), 1000.0), ("R", (x, y, back))]
    text = standard("G81 X5. Y5. Z-10. R-5.;", fifth=True)
    assert path(text) == expected_cycle(steps, fifth=True)
    tp = run(text)
    assert math.isclose(sum(tp.length[tp.kind == 1]) / 1000 * 60, 2.1, abs_tol=1e-9)


def test_e33_g82_drilling_with_dwell():
    """§G82 (P2. = 2 s, four holes): feed to Z, dwell 2 s, rapid out."""
    def steps(x, y, bottom, back):
        return [("F", (x, y, bottom), 1000.0), ("D", 2.0), ("R", (x, y, back))]
    assert path(standard("G82 X5. Y5. Z-10. R-5. P2.;", fifth=False)) == expected_cycle(steps, fifth=False)


def test_e34_g83_peck_drilling():
    """§G83 (Q3., d = 0.5): feed to -8, rapid to R (-5), rapid down to -8 + 0.5, feed to -10 (clipped from
    -11), rapid out."""
    def steps(x, y, bottom, back):
        return [("F", (x, y, -8.0), 1000.0), ("R", (x, y, -5.0)), ("R", (x, y, -7.5)),
                ("F", (x, y, -10.0), 1000.0), ("R", (x, y, back))]  # fmt: skip
    assert path(standard("G83 X5. Y5. Z-10. R-5. Q3.;", fifth=False)) == expected_cycle(steps, fifth=False)


def test_e35_g84_tapping_type_i():
    """§G84 (M03, no P, no Q: type I): feed to Z, reverse, feed back to R, reverse; with G98 rapid to the
    initial level. The note asking for CCW before G84 is a copy of G74's; the example's M03 is right."""
    def steps(x, y, bottom, back):
        out = [("F", (x, y, bottom), 1000.0), ("F", (x, y, -5.0), 1000.0)]
        return out + ([("R", (x, y, back))] if back != -5.0 else [])
    assert path(standard("G84 X5. Y5. Z-10. R-5.;", fifth=False)) == expected_cycle(steps, fifth=False)


def test_e36_g85_boring_feed_out():
    """§G85: feed to Z, feed back to R, with G98 rapid to the initial level."""
    def steps(x, y, bottom, back):
        out = [("F", (x, y, bottom), 1000.0), ("F", (x, y, -5.0), 1000.0)]
        return out + ([("R", (x, y, back))] if back != -5.0 else [])
    assert path(standard("G85 X5. Y5. Z-10. R-5.;", fifth=False)) == expected_cycle(steps, fifth=False)


def test_e37_g86_boring_spindle_stop():
    """§G86: feed to Z, spindle stop, rapid out, spindle on again."""
    def steps(x, y, bottom, back):
        return [("F", (x, y, bottom), 1000.0), ("R", (x, y, back))]
    text = standard("G86 X5. Y5. Z-10. R-5.;", fifth=False)
    assert path(text) == expected_cycle(steps, fifth=False)
    tp = run(text)
    assert tp.spindle_rpm[3:6].tolist() == [500.0, 0.0, 500.0]  # feed in; rapid out stopped; next hole


def test_e38_g87_back_boring():
    """§G87 example: ``G87 X5. Y5. Z10. R-30. Q5. P4.``, three holes, G99 in force. At the initial level
    (Z10): oriented stop, shift 5 against Pr4020's +X (to x - 5), rapid down to R (-30, below the part),
    shift back, feed up to Z10, dwell 4 s, oriented stop, shift to x - 5, rapid to the initial level (Z10
    already: no move), shift back. G87 returns to the initial level whatever G99 says."""
    text = ("F1000. S500;\nG90;\nG00 X0. Y0. Z10.;\nG17;\nG90 G99;\nM03;\nG87 X5. Y5. Z10. R-30. Q5. P4.;\n"
            "X15.; // hole2\nY15.; // hole3\nG80;\nM05;\nM02;\n")  # fmt: skip
    expected: list[tuple] = [("R", (0.0, 0.0, 10.0))]
    for x, y in HOLES[:3]:
        expected += [("R", (x, y, 10.0)), ("D", 0.0), ("R", (x - 5, y, 10.0)), ("R", (x - 5, y, -30.0)),
                     ("R", (x, y, -30.0)), ("F", (x, y, 10.0), 1000.0), ("D", 4.0), ("D", 0.0),
                     ("R", (x - 5, y, 10.0)), ("R", (x, y, 10.0))]  # fmt: skip
    assert path(text) == expected


def test_e39_g88_manual_retract():
    """§G88 (``P3.``: the comment says "dwell 2.0s"; the code is the oracle, 3 s): feed to Z, dwell 3 s,
    spindle stop and feed hold (the operator's manual retract, a 0 s exact stop; not simulated), feed back
    to R, with G98 rapid to the initial level."""
    def steps(x, y, bottom, back):
        out = [("F", (x, y, bottom), 1000.0), ("D", 3.0), ("D", 0.0), ("F", (x, y, -5.0), 1000.0)]
        return out + ([("R", (x, y, back))] if back != -5.0 else [])
    assert path(standard("G88 X5. Y5. Z-10. R-5. P3.;", fifth=False)) == expected_cycle(steps, fifth=False)


def test_e40_g89_boring_with_dwell():
    """§G89 (``P2.5`` = 2.5 s: the cycles' P is seconds with a decimal point): feed to Z, dwell 2.5 s, feed
    back to R, with G98 rapid to the initial level."""
    def steps(x, y, bottom, back):
        out = [("F", (x, y, bottom), 1000.0), ("D", 2.5), ("F", (x, y, -5.0), 1000.0)]
        return out + ([("R", (x, y, back))] if back != -5.0 else [])
    assert path(standard("G89 X5. Y5. Z-10. R-5. P2.5;", fifth=False)) == expected_cycle(steps, fifth=False)


# ---------------------------------------------------------------------- §G92, §G96/G97, T S F
def test_e41_g92_and_constant_surface_speed():
    """§G92 format ``G92 X20.0 Y15.0 Z20.0``: the tool's position becomes (20, 15, 20). §G96/G97 example 1:
    ``G92 S2000`` limits the spindle; ``G96 S130`` with the Ø10 tool needs N = 1000·130 / (π·10) = 4138
    r/min (the manual rounds to 4140), clamped to 2000. Without the G92 S limit: 4138. Example 2: ``G97
    S1300`` holds 1300 r/min."""
    tp = run("G92 X20.0 Y15.0 Z20.0 ;\nG01 X21. F100\n")
    assert tp.start[0].tolist() == [0.0, 0.0, 0.0] and tp.end[0].tolist() == [1.0, 0.0, 0.0]
    offsets = {"D": {2: 5.0}}
    clamped = run("D2\nG92 S2000;\nG96 S130 M03;\nG01 X1. F100\n", tool_offsets=offsets)
    assert clamped.spindle_rpm.tolist() == [2000.0]
    free = run("D2\nG96 S130 M03;\nG01 X1. F100\n", tool_offsets=offsets)
    assert math.isclose(free.spindle_rpm[0], 1000 * 130 / (math.pi * 10), abs_tol=1e-9)
    assert round(free.spindle_rpm[0]) == 4138
    assert run("G97 S1300 M03 ;\nG01 X1. F100\n").spindle_rpm.tolist() == [1300.0]


def _pattern_program(block: str, feed: int) -> str:
    return f"G91 ;\nG81 Z-10.0 R5.0 K0 F{feed} ;\n{block}\nG80 ;\n"


def test_e42_g134_bolt_circle():
    """§G134 example: G92 X500 Y100 makes the tool (machine 0, 0) the work point (500, 100); in G91 the
    centre is (500 + 200, 100 + 100) = (700, 200) work = machine (200, 100); radius 100, the first hole at
    20°, six holes 60° apart (K > 0: counter-clockwise). In G91 R5.0 is measured from the initial level
    (Z0) and Z-10.0 from R: R at +5, bottom at -5 (the example predates the manual's 2006 Z/R revision)."""
    text = "G92 X500.0 Y100.0 ;\nG91 G81 Z-10.0 R5.0 K0 F200 ;\nG134 X200.0 Y100.0 I100.0 J20.0 K6 ;\n" \
           "G80 ;\nG90 G0 X0.0 Y0.0 ;\n"  # fmt: skip
    expected = [polar_point(100, 20 + 60 * k, (200, 100)) for k in range(6)]
    found = holes(text, -5.0)
    assert len(found) == 6 and all(close(h, e) for h, e in zip(found, expected, strict=True))
    assert path(text)[-1] == ("R", (-500.0, -100.0, 0.0))  # back to the work zero


def test_e43_g135_angular_line():
    """§G135 example: from (0, 0) in G91 the start is (200, 100); five holes 100 apart at 30°."""
    text = _pattern_program("G135 X200.0 Y100.0 I100.0 J30.0 K5 ;", 100)
    expected = [(200 + 100 * k * math.cos(math.radians(30)), 100 + 100 * k * math.sin(math.radians(30)))
                for k in range(5)]  # fmt: skip
    found = holes(text, -5.0)
    assert len(found) == 5 and all(close(h, e) for h, e in zip(found, expected, strict=True))


def test_e44_g136_arc_with_angle_pitch_in_thousandths():
    """§G136 example: centre (300, 100), radius 300, first hole at 10°, ``P15000`` = 15° (no decimal point:
    0.001°), six holes: 10°, 25°, 40°, 55°, 70°, 85°."""
    text = _pattern_program("G136 X300.0 Y100.0 I300.0 J10.0 P15000 K6 ;", 100)
    expected = [polar_point(300, 10 + 15 * k, (300, 100)) for k in range(6)]
    found = holes(text, -5.0)
    assert len(found) == 6 and all(close(h, e) for h, e in zip(found, expected, strict=True))


def test_e45_g137_1_grid():
    """§G137.1 example: start (300, -100), P10 holes 50 apart in X, K8 rows 100 apart in Y: 80 holes, row by
    row, each row back the way the last came (the drilling order is our reading: the figure is lost)."""
    text = _pattern_program("G137.1 X300.0 Y-100.0 I50.0 P10 J100.0 K8 ;", 20)
    expected = []
    for row in range(8):
        cols = range(10) if row % 2 == 0 else range(9, -1, -1)
        expected += [(300 + 50.0 * c, -100 + 100.0 * row) for c in cols]
    assert holes(text, -5.0) == expected
    assert {r[2] for r in path(text) if r[0] == "F"} == {20.0}


def test_e46_t_s_f_one_liners():
    """§T, §S, §F: ``T03 M06`` changes to tool 3; ``G97 S500 M03`` 500 r/min; ``G94 … F300`` 300 mm/min;
    ``G95 … F0.5`` 0.5 mm/rev, i.e. 0.5 × S = 250 mm/min at S500."""
    tp = run("T03 M06;\nG97 S500 M03;\nG94 G01 X100.0 Y100.0 F300;\nG95 G01 X200.0 Y100.0 F0.5;\n")
    assert tp.tool.tolist() == [3, 3] and tp.spindle_rpm.tolist() == [500.0, 500.0]
    assert tp.feed.tolist() == [300.0, 250.0]
