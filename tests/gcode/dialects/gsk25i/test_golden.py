"""Golden traces from the manual's worked examples (docs/gsk25i_examples.md) that fall inside this issue's
scope.

Each expected trace is worked out by hand from the example's geometry; the reasoning is next to it. The
comparison covers every record key of the ``cnc-gym trace`` contract.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

from gcode_helpers import close, program_error, records

DEG = math.degrees


def assert_trace(actual: list[dict], expected: list[dict]) -> None:
    assert len(actual) == len(expected), (actual, expected)
    for got, want in zip(actual, expected, strict=True):
        assert set(want) <= set(got), (got, want)
        for key, value in want.items():
            if key in ("kind", "plane", "line"):
                assert got[key] == value, (key, got, want)
            else:
                assert close(got[key], value, 1e-6), (key, got[key], value)


# X2 (§2.4): modality of G0/G1/F/Y and the power-on G00.
X2 = """O00001
G0 X100 Y100
X20 Y30
G1 X50 Y50 F300
X100
M30
"""


def test_x2_modal_program():
    assert_trace(records(X2), [
        {"kind": "rapid", "line": 2, "start": [0, 0, 0], "end": [100, 100, 0]},
        {"kind": "rapid", "line": 3, "start": [100, 100, 0], "end": [20, 30, 0]},
        {"kind": "line", "line": 4, "start": [20, 30, 0], "end": [50, 50, 0], "feed": 300},
        {"kind": "line", "line": 5, "start": [50, 50, 0], "end": [100, 50, 0], "feed": 300},
    ])  # fmt: skip


# X57 (§3.5.2): the classic contour, without its G41 D07 (test_compensation.py runs it with), with
# two repairs: N7 restored from the Fanuc original, and N6's centre I650 (the printed
# I250 J0 fails the radius check: see test_x57_as_printed_fails_the_radius_check).
X57 = """G92 X0 Y0 Z0
N1 G90 G17 G00 X250.0 Y550.0
N2 G01 Y900.0 F150
N3 X450.0
N4 G03 X500.0 Y1150.0 I-600.0 J250.0
N5 G02 X900.0 I200.0 J150.0
N6 G03 X950.0 Y900.0 I650.0 J0
N7 G01 X1150.0
N8 Y550.0
N9 X700.0 Y650.0
N10 X250.0 Y550.0
N11 G00 G40 X0 Y0
"""


def test_x57_contour():
    # N4: start (450, 900), centre (450-600, 900+250) = (-150, 1150), r = hypot(600, 250) = 650; the end
    #     (500, 1150) is 650 right of the centre. CCW from atan2(-250, 600) to 0: +atan(250/600) = 22.62°.
    # N5: start (500, 1150), centre (700, 1300), r = 250; end (900, 1150) is at (200, -150) from the
    #     centre. The start is at (-200, -150): the two radii enclose acos(-0.28) = 106.26°, and going CW
    #     from the start (216.87°) to the end (-36.87°) passes over the top: -(360 - 106.26) = -253.74°.
    # N6: start (900, 1150), centre (1550, 1150), r = 650; end (950, 900) at (-600, -250): CCW from 180° to
    #     180° + atan(250/600): +22.62°.
    quarter = DEG(math.atan2(250, 600))
    n5 = -(360 - DEG(math.acos((-200 * 200 + 150 * 150) / 250**2)))
    assert_trace(records(X57), [
        {"kind": "rapid", "line": 2, "end": [250, 550, 0]},
        {"kind": "line", "line": 3, "end": [250, 900, 0], "feed": 150},
        {"kind": "line", "line": 4, "end": [450, 900, 0], "feed": 150},
        {"kind": "arc", "line": 5, "start": [450, 900, 0], "end": [500, 1150, 0], "center": [-150, 1150, 0],
         "plane": "XY", "sweep_deg": quarter, "radius": 650, "feed": 150},
        {"kind": "arc", "line": 6, "end": [900, 1150, 0], "center": [700, 1300, 0], "plane": "XY",
         "sweep_deg": n5, "radius": 250, "feed": 150},
        {"kind": "arc", "line": 7, "end": [950, 900, 0], "center": [1550, 1150, 0], "plane": "XY",
         "sweep_deg": quarter, "radius": 650, "feed": 150},
        {"kind": "line", "line": 8, "end": [1150, 900, 0], "feed": 150},
        {"kind": "line", "line": 9, "end": [1150, 550, 0], "feed": 150},
        {"kind": "line", "line": 10, "end": [700, 650, 0], "feed": 150},
        {"kind": "line", "line": 11, "end": [250, 550, 0], "feed": 150},
        {"kind": "rapid", "line": 12, "end": [0, 0, 0]},
    ])  # fmt: skip


def test_x57_as_printed_fails_the_radius_check():
    # N6 as printed, "G03 X950.0 Y900.0 I250.0 J0": centre (1150, 1150), start radius 250, end radius
    # hypot(950-1150, 900-1150) = 320.16: far beyond P1810 = 0.01 mm → alarm 20 on N6's line.
    err = program_error(X57.replace("I650.0 J0", "I250.0 J0"), file="x57.nc")
    assert (err.code, err.alarm, err.line) == ("arc-radius-mismatch", 20, 7)
    assert str(err).startswith("x57.nc:7: ")


# X10 + X13 + X7 in one program (§3.2.3, §3.2.6, §3.2.1): G92 origin, I/J arcs, dwells, F from a G00.
X10 = """%
O0010
N1 G92 X200.0 Y40.0 Z0
N2 G00 X200 Y40 F300
N3 G90 G03 X140.0 Y100.0 I-60.0
N4 G02 X120.0 Y60.0 I-50.0
N5 G04 X3.8
N6 G04 P3800
N7 M30
%
"""


def test_x10_arcs_and_dwells():
    # G92 at the machine origin: machine = program - (200, 40, 0). N2 is no motion (already there) but its
    # F300 becomes the cutting feed (§3.2.1). Arcs as in test_motion.test_worked_example_x10_*.
    assert_trace(records(X10), [
        {"kind": "arc", "line": 5, "start": [0, 0, 0], "end": [-60, 60, 0], "center": [-60, 0, 0],
         "plane": "XY", "sweep_deg": 90, "radius": 60, "feed": 300},
        {"kind": "arc", "line": 6, "start": [-60, 60, 0], "end": [-80, 20, 0], "center": [-110, 60, 0],
         "plane": "XY", "sweep_deg": -DEG(math.atan2(40, 30)), "radius": 50, "feed": 300},
        {"kind": "dwell", "line": 7, "seconds": 3.8},
        {"kind": "dwell", "line": 8, "seconds": 3.8},
    ])  # fmt: skip
