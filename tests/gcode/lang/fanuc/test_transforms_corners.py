"""Optional-angle chamfering ``,L`` and corner rounding ``,R`` (§3.2.11).

Closed forms used for the expectations (independent of the code):

* a chamfer ``,L`` cuts each block ``L`` from the virtual corner, along the block;
* a fillet ``,R`` between two lines turning by δ touches each line ``R·tan(δ/2)`` from the corner, its
  centre lies ``R`` from both lines on the inner side, and it sweeps δ (CCW for a left turn);
* a fillet between a line and an arc of radius ρ has its centre ``R`` from the line and ``ρ ± R`` from
  the arc's centre (``+`` when it lies outside the arc's circle).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import itertools
import math

import pytest
from gcode_helpers import close, moves, program_error, success_share, tally
from hypothesis import given, settings
from hypothesis import strategies as st

X19 = ("N001 G92 G90 X0 Y0\nN002 G00 X10.0 Y10.0\nN003 G01 X50.0 F10.0,L5.0\nN004 Y25.0,R8.0\n"
       "N005 G03 X80.0 Y50.0 R30.0,R8.0\nN006 G01 X50.0,R8.0\nN007 Y70.0,L5.0\nN008 X10.0,L5.0\nN009 Y10.0\n"
       "N010 G00 X0 Y0\nN011 M0\n")  # fmt: skip


def tangent(record, at_end: bool):
    """Unit travel direction of a trace record at its end or start."""
    if record["kind"] != "arc":
        d = [b - a for a, b in zip(record["start"], record["end"], strict=True)]
        n = math.hypot(d[0], d[1])
        return d[0] / n, d[1] / n
    q = record["end"] if at_end else record["start"]
    c = record["center"]
    ru, rv = q[0] - c[0], q[1] - c[1]
    n = math.hypot(ru, rv)
    s = 1.0 if record["sweep_deg"] > 0 else -1.0
    return -rv / n * s, ru / n * s


def test_worked_example_x19_chamfers_and_fillets():
    # §3.2.11, with the duplicated N006 of the text removed (docs/gsk25i_examples.md X19).
    out = moves(X19)
    pts = [(r["start"][:2], r["end"][:2], r["kind"], r["line"]) for r in out]
    # N003 X50 with ,L5 then N004 +Y: N003 stops 5 short of (50, 10); the chamfer ends 5 up N004.
    assert pts[1] == ([10.0, 10.0], [45.0, 10.0], "line", 3)
    assert pts[2] == ([45.0, 10.0], [50.0, 15.0], "line", 3)  # the chamfer belongs to the ,L block
    # N006 (to -X) with ,R8 then N007 (+Y): a 90° right turn; the fillet touches each line 8·tan(45°) = 8
    # from the corner (50, 50), centre (58, 58), 90° clockwise.
    fillet = next(r for r in out if r["line"] == 6 and r["kind"] == "arc")
    assert close(fillet["start"][:2], [58.0, 50.0]) and close(fillet["end"][:2], [50.0, 58.0])
    assert close(fillet["center"][:2], [58.0, 58.0]) and close(fillet["sweep_deg"], -90.0)
    # N007 +Y with ,L5 then N008 -X; N008 -X with ,L5 then N009 -Y: chamfers 5 from (50,70) and (10,70).
    lines = [(r["start"][:2], r["end"][:2]) for r in out if r["line"] in (7, 8, 9)]
    assert lines == [([50.0, 58.0], [50.0, 65.0]), ([50.0, 65.0], [45.0, 70.0]), ([45.0, 70.0], [15.0, 70.0]),
                     ([15.0, 70.0], [10.0, 65.0]), ([10.0, 65.0], [10.0, 10.0])]  # fmt: skip
    # N004 (+Y) with ,R8 into the N005 arc, and N005 with ,R8 into N006: the N005 circle, worked out from
    # its R form: chord (50,25)→(80,50), a CCW minor arc has its centre left of the chord.
    du, dv = 30.0, 25.0
    chord = math.hypot(du, dv)
    h = math.sqrt(30.0**2 - (chord / 2) ** 2)
    arc_centre = (65.0 - dv / chord * h, 37.5 + du / chord * h)
    fillets = [r for r in out if r["kind"] == "arc" and r["line"] in (4, 5) and close(r["radius"], 8.0)]
    assert len(fillets) == 2
    first, second = (r["center"][:2] for r in fillets)
    # Fillet 1: right turn from +Y into the arc, centre on the right of x = 50 (x = 58) and outside the
    # N005 circle (30 + 8); fillet 2: left turn from the arc into -X, centre 8 below y = 50 and inside the
    # circle (30 - 8).
    assert close(first[0], 58.0) and close(math.dist(first, arc_centre), 38.0)
    assert close(second[1], 42.0) and close(math.dist(second, arc_centre), 22.0)
    n005 = next(r for r in out if r["line"] == 5 and close(r["radius"], 30.0))
    assert close(n005["center"][:2], list(arc_centre))
    # The whole contour is continuous and tangent-continuous at every fillet join.
    for a, b in itertools.pairwise(out):
        assert close(a["end"], b["start"], 1e-5)
        radii = (round(a.get("radius", 0), 6), round(b.get("radius", 0), 6))
        if "arc" in (a["kind"], b["kind"]) and 8.0 in radii:
            assert close(tangent(a, True), tangent(b, False), 1e-5)


@settings(max_examples=60, deadline=None)
@given(heading=st.floats(0, 360), turn=st.floats(10, 150) | st.floats(-150, -10),
       radius=st.floats(0.5, 5), length=st.floats(20, 60))  # fmt: skip
def test_line_line_fillet_matches_the_closed_form(heading, turn, radius, length):
    a0, a1 = math.radians(heading), math.radians(heading + turn)
    corner = (length * math.cos(a0), length * math.sin(a0))
    end = (corner[0] + length * math.cos(a1), corner[1] + length * math.sin(a1))
    text = (f"G01 X{corner[0]:.4f} Y{corner[1]:.4f} F100 ,R{radius:.4f}\n"
            f"X{end[0]:.4f} Y{end[1]:.4f}\n")  # fmt: skip
    out = moves(text)
    fillet = out[1]
    r = round(radius, 4)
    delta = math.radians(turn)
    t = r * math.tan(abs(delta) / 2)
    assert fillet["kind"] == "arc" and close(fillet["radius"], r, 1e-4)
    assert close(math.dist(fillet["start"][:2], corner), t, 2e-4)
    assert close(math.dist(fillet["end"][:2], corner), t, 2e-4)
    assert close(fillet["sweep_deg"], turn, 1e-2)
    assert close(out[0]["end"], fillet["start"], 1e-6) and close(out[2]["start"], fillet["end"], 1e-6)


def test_chamfer_on_an_arc_is_measured_along_the_arc():
    # A line +Y from (10, -10) to (10, 0) with ,L2 into a CW quarter circle of radius 10 about (10, -10)
    # (to (20, -10)): a 90° right turn. The line is cut 2 short: (10, -2). The arc is cut by 2 mm of arc
    # length, 0.2 rad clockwise from its start angle 90°; 90° - 0.2 rad of it remain.
    out = moves("G00 X10 Y-10\nG01 Y0 F100 ,L2\nG02 X20 Y-10 R10\n")
    a = math.pi / 2 - 0.2
    assert close(out[1]["end"][:2], [10.0, -2.0])
    assert close(out[2]["end"][:2], [10 + 10 * math.cos(a), -10 + 10 * math.sin(a)])
    assert close(out[3]["sweep_deg"], -(90.0 - math.degrees(0.2)), 1e-4)
    assert close(out[3]["end"][:2], [20.0, -10.0])


def test_chamfer_in_incremental_mode_and_consecutive_corners():
    out = moves("G91 G01 X10 F100 ,L1\nY10 ,L1\nX-10\n")
    assert [r["end"][:2] for r in out] == [[9.0, 0.0], [10.0, 1.0], [10.0, 9.0], [9.0, 10.0], [0.0, 10.0]]


def test_chamfer_follows_the_rotation():
    # G68 rotates the finished contour: the same program rotated by 90° about the origin.
    plain = moves("G01 X10 F100 ,L2\nY10\n")
    rotated = moves("G68 X0 Y0 R90\nG01 X10 F100 ,L2\nY10\n")
    for p, q in zip(plain, rotated, strict=True):
        assert close(q["end"][:2], [-p["end"][1], p["end"][0]])


@pytest.mark.parametrize(
    ("text", "code"),
    [
        ("G01 X10 F100 ,L20\nY10\n", "bad-corner"),  # longer than the block (§3.2.11)
        ("G01 X10 F100 ,R20\nY10\n", "bad-corner"),  # the fillet does not fit
        ("G01 X10 F100 ,L2\nM08\nY10\n", "bad-corner"),  # the next block must move (§3.2.11)
        ("G01 X10 F100 ,L2\nG00 Y10\n", "bad-corner"),
        ("G01 X10 F100 ,L2\n", "bad-corner"),  # nothing follows
        ("G01 X10 F100 ,L2\nX20\n", "bad-corner"),  # straight on: no corner
        ("G01 X10 F100 ,L2\nX0\n", "bad-corner"),  # reversal
        ("G01 X10 F100 ,L2 ,R2\nY10\n", "bad-combination"),
        ("G16\nG01 X10 Y0 F100 ,L2\nY90\n", "bad-corner"),  # not in polar mode (§3.2.16)
        ("G01 X10 Z5 F100 ,L2\nY10\n", "bad-corner"),  # in the plane only (§3.2.11)
        ("G00 X10 ,L2\nY10\n", "unused-word"),  # G00 has no chamfer
        ("G01 X10 F100 ,L0\nY10\n", "bad-corner"),
        ("G01 X10 F100 ,L2\nG18 Z10\n", "bad-corner"),  # the next block in another plane
        ("G01 X10 F100 ,C2\nY10\n", "bad-character"),  # GSK uses ,L, not Fanuc's ,C
        ("G92 X0 Y0\nG01 X10 F100 ,L2\nY10\n", "bad-corner"),  # right after G92 (§3.2.11)
        ("G01 F100\nG55\nX10 ,L2\nY10\n", "bad-corner"),  # right after G54-G59
        ("G52 X1\nG01 X10 F100 ,R2\nY10\n", "bad-corner"),
        ("G28 X0\nG01 X10 F100 ,L2\nY10\n", "bad-corner"),  # right after a reference return
        ("G18\nG17\nG01 X10 F100 ,L2\nY10\n", "bad-corner"),  # right after a plane change
        ("G01 X10 F100 ,L2\nG92 X0\nY10\n", "bad-corner"),  # a coordinate change in between
        ("G09 G01 X10 F100 ,L2\nY10\n", "bad-corner"),  # a group-00 code in the block (§3.2.11)
    ],
)  # fmt: skip
def test_corner_errors(text, code):
    assert program_error(text).code == code


def test_corner_error_names_the_line_of_the_corner_block():
    err = program_error("G01 X1 F100\nG01 X10 ,L2\n")
    assert err.line == 2


block = st.tuples(st.sampled_from(["G01", "G02", "G03"]), st.integers(-30, 30), st.integers(-30, 30),
                  st.integers(45, 80), st.sampled_from(["", ",L1", ",R1", ",L3", ",R4"]))  # fmt: skip


@success_share(0.2)
@settings(max_examples=80, deadline=None)
@given(st.lists(block, min_size=2, max_size=8),
       st.sampled_from(["", "G68 X3 Y-2 R30\n", "G51 X0 Y0 I2 J-1\n"]))  # fmt: skip
def test_random_contours_with_corners_stay_continuous(blocks, transform):
    from cnc_gym.errors import ProgramError
    from cnc_gym.gcode import interpret

    lines = [transform + "G00 X0 Y0\nF100"]
    for code, x, y, r, corner in blocks:
        lines.append(f"{code} X{x} Y{y}" + (f" R{r}" if code != "G01" else "") + f" {corner}".rstrip())
    try:
        toolpath = interpret("\n".join(lines) + "\nG01 X50 Y50\n")
    except ProgramError as err:
        assert err.code and err.line is not None
        tally(False)
        return
    tally(True)
    records = toolpath.to_records()
    moves_only = [r for r in records if r["kind"] != "dwell"]
    for a, b in itertools.pairwise(moves_only):
        assert close(a["end"], b["start"], 1e-4)


def test_chamfer_and_fillet_are_compensated_with_the_contour():
    # G41 D1 (radius 2) on a CCW square 20 x 20: the left side is the inside. The chamfer line x - y = 17
    # (from (17,0) to (20,3)) moves 2 inwards: x - y = 17 - 2·√2; it meets the offset sides y = 2 and
    # x = 18 there. The R4 fillet about (16, 16) becomes an R2 arc about the same centre.
    text = ("G10 L12 P1 R2\nG00 X-10 Y-10\nG41 D1 G01 X0 Y0 F100\nX20 ,L3\nY20 ,R4\nX0\nY0\n"
            "G40 G00 X-10 Y-10\n")  # fmt: skip
    out = moves(text)
    c = 17 - 2 * math.sqrt(2)
    chamfer = next(r for r in out if r["line"] == 4 and r["start"][1] == 2.0 and r["end"][1] != 2.0)
    assert close(chamfer["start"][:2], [c + 2, 2.0]) and close(chamfer["end"][:2], [18.0, 18.0 - c])
    fillet = next(r for r in out if r["kind"] == "arc")
    assert close(fillet["center"][:2], [16.0, 16.0]) and close(fillet["radius"], 2.0)
    assert close(fillet["sweep_deg"], 90.0)


def test_corner_restrictions_last_only_one_block():
    # One block after the change the restriction is over; G04 is the allowed group-00 code (§3.2.11);
    # G17 in G17 is no plane change.
    assert len(moves("G92 X0 Y0\nG04 X0.1\nG01 X10 F100 ,L2\nY10\n")) == 3
    assert len(moves("G92 X0 Y0\nG01 X5 F100\nX10 ,L2\nY10\n")) == 4
    assert len(moves("G17 G01 X10 F100 ,L2\nY10\n")) == 3


def test_a_corner_that_takes_all_of_a_block_with_its_own_corner_is_an_error():
    # Found by the random-contour property: ,L1 on a 1 mm block consumes all of the next 1 mm block, which
    # then has nothing left for its own ,L1: alarm-style error (§3.2.11), not a crash.
    err = program_error("G00 X0 Y0\nF100\nG01 X0 Y1 ,L1\nG01 X1 Y1 ,L1\nG01 X50 Y50\n")
    assert err.code == "bad-corner" and err.line == 4
