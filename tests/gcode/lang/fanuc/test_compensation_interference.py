"""The interference check and its correction before alarm 41 (manual §3.5.3, §3.5.2, docs/gsk25i_alarms.md
T6).

The rule as we read the manual (figures lost; the text is a translation of Fanuc's "correction of
interference in advance"): the tool-centre points at a corner are its *vectors*, in path order. Block B
runs from the last vector at its start corner to the first vector at its end corner. That pair is checked
(check (a): a line's movement runs 90°-270° against its programmed direction, or an arc's offset radius is
negative; check (b): an arc's sweep differs from the programmed one by more than 180°). An interfering
pair is ignored (V4/V5, then V3/V6, V2/V7 …) and the next pair out is checked; once a vector is dropped an
arc runs as a straight line. The last vector at a corner is never dropped: when only one side has a vector
to spare, only that one goes ("one vector is ignored and the tool moves toward the 2nd vector", the step
smaller than the tool radius, §3.5.3); when neither side has one (a single pair from the start, or
interference left after correcting) it is alarm 41.

Every expected path below is worked out by hand (offset lines and circles, their intersections) in the
comments, independently of ``cnc_gym.gcode.lang.fanuc.compensation``.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from gcode_helpers import close, moves, program_error, success_share, tally
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import get_dialect, interpret
from cnc_gym.gcode.lang.fanuc.compensation.geometry import (
    CompensationError,
    PlaneElement,
    block_interference,
    compensate,
    correct_interference,
)
from cnc_gym.toolpath import SegmentKind


def ends(text: str) -> list[tuple[str, int, list[float]]]:
    return [(r["kind"], r["line"], r["end"][:2]) for r in moves(text)]


def assert_path(text: str, expected) -> None:
    got = ends(text)
    assert len(got) == len(expected), got
    for (kind, line, point), (e_kind, e_line, e_point) in zip(got, expected, strict=True):
        assert (kind, line) == (e_kind, e_line) and close(point, e_point), (got, expected)


# ------------------------------------------------------------------ the pairing order, on bare vectors
PLUS_X = PlaneElement((0.0, 0.0), (10.0, 0.0))  # a line block along +x: a pair interferes iff x decreases


def test_pairs_are_dropped_from_the_inside_out_until_one_does_not_interfere():
    # §3.5.3 (Fanuc's example 2): V1..V4 at the start corner, V5..V8 at the end corner. V4 -> V5
    # runs from x = 9 back to x = 1 (interference: ignore both), V3 -> V6 from 6 back to 4 (ignore),
    # V2 -> V7 from 3 on to 7 (no interference: the check stops). Path V1 -> V2 -> V7 -> V8.
    starts = [(0.0, 1.0), (3.0, 1.0), (6.0, 1.0), (9.0, 1.0)]
    ends_at = [(1.0, 1.0), (4.0, 1.0), (7.0, 1.0), (12.0, 1.0)]
    kept_starts, kept_ends, as_line = correct_interference(PLUS_X, 1.0, starts, ends_at)
    assert kept_starts == starts[:2] and kept_ends == ends_at[2:] and as_line


def test_the_last_vectors_are_kept_and_a_clean_last_pair_is_the_corrected_path():
    # Fanuc's example 1: V4/V5, V3/V6, V2/V7 all interfere; V1 -> V8 (x 0 -> 5) does not: the tool moves
    # straight from V1 to V8.
    starts = [(0.0, 1.0), (3.0, 1.0), (6.0, 1.0), (9.0, 1.0)]
    ends_at = [(1.0, 1.0), (4.0, 1.0), (2.0, 1.0), (5.0, 1.0)]
    assert correct_interference(PLUS_X, 1.0, starts, ends_at)[:2] == ([starts[0]], [ends_at[-1]])


def test_interference_left_after_correcting_is_alarm_41():
    # §3.5.3: V2/V5 interfere and are ignored; V1 -> V6 still runs back (x 5 -> 4): alarm 41.
    with pytest.raises(CompensationError) as info:
        correct_interference(PLUS_X, 1.0, [(5.0, 1.0), (8.0, 1.0)], [(2.0, 1.0), (4.0, 1.0)], line=7)
    assert (info.value.code, info.value.line) == ("comp-interference", 7)
    assert "after ignoring 2 corner vectors" in str(info.value)


def test_a_single_interfering_pair_from_the_start_is_alarm_41():
    # §3.5.3: "only one pair of vectors ... interfered at the start of checking": nothing to ignore.
    with pytest.raises(CompensationError, match="check \\(a\\)"):
        correct_interference(PLUS_X, 1.0, [(5.0, 1.0)], [(4.0, 1.0)])


def test_only_the_side_with_a_vector_to_spare_gives_one_up():
    # One start vector (kept: the last at its corner), two end vectors: V1 -> V5 runs back, V5 is
    # ignored, V1 -> V6 runs forward.
    kept = correct_interference(PLUS_X, 1.0, [(5.0, 1.0)], [(4.0, 1.0), (9.0, 1.0)])
    assert kept == ([(5.0, 1.0)], [(9.0, 1.0)], True)


def test_an_arc_is_checked_as_an_arc_then_as_a_straight_line_along_its_chord():
    # A CW quarter about (0, 0) from (0, 10) to (10, 0) (sweep -90°), offset 1 to the left = outside
    # (R + 1 = 11). Start vector at 90°, end vector at 100°: clockwise from 90° to 100° is -350°, so
    # check (b) fires. The end corner has a second vector at (11, -1); after dropping the first, the
    # straight move (0, 11) -> (11, -1) runs along the chord direction (+1, -1): no interference.
    arc = PlaneElement((0.0, 10.0), (10.0, 0.0), (0.0, 0.0), -math.pi / 2)
    at_100 = (11 * math.cos(math.radians(100)), 11 * math.sin(math.radians(100)))
    assert "check (b)" in block_interference(arc, 1.0, (0.0, 11.0), at_100)
    assert block_interference(arc, 1.0, (0.0, 11.0), (11.0, 0.0)) is None
    kept = correct_interference(arc, 1.0, [(0.0, 11.0)], [at_100, (11.0, -1.0)])
    assert kept == ([(0.0, 11.0)], [(11.0, -1.0)], True)


def test_an_inner_arc_equal_to_the_offset_is_alarm_38_not_corrected():
    # §3.5.3: radius R = offset on the centre side: the tool-centre circle has radius 0.
    arc = PlaneElement((0.0, 0.0), (2.0, 0.0), (1.0, 0.0), math.pi)  # CCW half circle, R 1
    with pytest.raises(CompensationError) as info:
        correct_interference(arc, 1.0, [(0.0, 0.0), (1.0, 1.0)], [(2.0, 0.0), (3.0, 1.0)])
    assert info.value.code == "comp-arc-centre"


# ------------------------------------------------------------------------- whole programs, by hand
def test_dip_narrower_than_the_tool_is_bridged_by_a_straight_line():
    # +x to (10, 0), a CCW half circle R 5 about (15, 0) dipping to (15, -5), +x on; G41 r = 6 (tool
    # above). The arc's offset radius is 5 - 6 < 0 (check (a)). Its corners turn 90° to the right
    # (outer), and the offset circle (radius 1) never meets the offset lines y = 6: each corner has two
    # vectors, perpendicular to either block: (10, 6), (16, 0) at the start and (14, 0), (20, 6) at
    # the end. (16, 0) -> (14, 0) interferes; both are ignored; (10, 6) -> (20, 6) runs along the chord
    # (+x): the arc becomes this straight line (§3.5.3). No alarm, and the tool (r 6 at y = 6) never
    # enters the dip.
    text = "G10 L12 P1 R6\nG00 X-20\nG01 G41 D1 X-10 Y0 F100\nX10\nG03 X20 Y0 I5 J0\nG01 X30\nG40 X40\n"
    assert_path(text, [
        ("rapid", 2, (-20, 0)),
        ("line", 3, (-10, 6)),  # start-up, the next block straight on: perpendicular vector
        ("line", 4, (10, 6)),
        ("line", 5, (20, 6)),  # the arc block, corrected into a line
        ("line", 6, (30, 6)),
        ("line", 7, (40, 0)),  # cancel
    ])  # fmt: skip


def test_step_smaller_than_the_tool_radius_with_an_arc_ignores_one_vector():
    # §3.5.3: +x to (10, 0), a CCW quarter R 1 about (10, 1) up to (11, 1), +x at y = 1; G41 r = 5.
    # Start corner: tangent (smooth), one vector (10, 5). End corner: up then +x, a right turn (outer);
    # the offset circle (radius |1 - 5| = 4) does not reach y = 6, so two vectors: perpendicular to the
    # arc's end, (11, 1) + 5·(-1, 0) = (6, 1), and perpendicular to the next block, (11, 6). The arc's
    # offset radius is negative (check (a)); (10, 5) is the last vector at its corner, so only (6, 1)
    # is ignored and the tool goes straight to the 2nd vector (11, 6). No alarm.
    text = "G10 L12 P1 R5\nG00 X-20\nG01 G41 D1 X-10 Y0 F100\nX10\nG03 X11 Y1 I0 J1\nG01 X20\nG40 X30\n"
    assert_path(text, [
        ("rapid", 2, (-20, 0)), ("line", 3, (-10, 5)), ("line", 4, (10, 5)),
        ("line", 5, (11, 6)),  # the arc block, one vector ignored
        ("line", 6, (20, 6)), ("line", 7, (30, 1)),
    ])  # fmt: skip


def test_step_smaller_than_the_tool_radius_with_a_line_needs_no_correction():
    # The same step as a line (Fanuc: "if the step is linear, no alarm; an uncut part remains"):
    # +x then +y is an inner corner for G41: y = 5 meets x = 10 - 5 at (5, 5); +y then +x an outer 90°
    # corner: x = 5 meets y = 6 at (5, 6). The step's own move (5, 5) -> (5, 6) runs up, as programmed.
    text = "G10 L12 P1 R5\nG00 X-20\nG01 G41 D1 X-10 Y0 F100\nX10\nY1\nX20\nG40 X30\n"
    assert_path(text, [
        ("rapid", 2, (-20, 0)), ("line", 3, (-10, 5)), ("line", 4, (5, 5)), ("line", 5, (5, 6)),
        ("line", 6, (20, 6)), ("line", 7, (30, 1)),
    ])  # fmt: skip


SHORT_BACK = "G10 L12 P1 R2\nG00 X-10 Y0\nG01 G42 D1 X0 Y0 F100\nX10\nX{x} Y{y}\nX20\nG40 X30\n"


def test_short_line_after_an_acute_corner_drops_its_extension_point():
    # G42 r = 2 (tool on the right). A: +x to (10, 0). B: back up-left along t = (-1, 1)/√2 for
    # L = 1.75·√2 = 2.47 to (8.25, 1.75). C: +x. A -> B turns left by 135°: outer for G42, alpha 45°
    # < 90°: extension points. A runs on r past its offset end: q1 = (10, -2) + 2·(1, 0) = (12, -2);
    # q2 = B's offset start minus r along t: (10, 0) + 2·(1, 1)/√2 - 2·(-1, 1)/√2 = (10 + 2√2, 0).
    # B -> C turns right by 135°: inner: B's right offset line (points p with (1, 1)/√2·p = 10/√2 + 2)
    # meets y = 1.75 - 2 = -0.25 at x = 10 + 2√2 + 0.25 = 13.078.
    # B's move q2 -> (13.078, -0.25) runs along (+0.25, -0.25): against t, interference. The end corner
    # has one vector (kept); q2 is ignored; q1 -> (13.078, -0.25) is (1.078, 1.75), whose dot with t is
    # (1.75 - 1.078)/√2 > 0: corrected, no alarm.
    corner_bc = (10 + 2 * math.sqrt(2) + 0.25, -0.25)
    assert_path(SHORT_BACK.format(x=8.25, y=1.75), [
        ("rapid", 2, (-10, 0)), ("line", 3, (0, -2)), ("line", 4, (12, -2)),
        ("line", 5, corner_bc),  # no move to q2: it was ignored
        ("line", 6, (20, -0.25)), ("line", 7, (30, 1.75)),
    ])  # fmt: skip


def test_short_line_still_interfering_after_correction_is_alarm_41():
    # The same with L = 1.2·√2 = 1.70 (to (8.8, 1.2)): the inner corner is at y = 1.2 - 2 = -0.8,
    # x = 10 + 2√2 + 0.8 = 13.628; after ignoring q2, q1 = (12, -2) -> (13.628, -0.8) is (1.628, 1.2),
    # whose dot with t = (-1, 1)/√2 is negative: interference with the last vectors: alarm 41 on B.
    err = program_error(SHORT_BACK.format(x=8.8, y=1.2))
    assert (err.code, err.alarm, err.line) == ("comp-interference", 41, 5)
    assert "after ignoring 1 corner vector" in str(err)


def test_groove_narrower_than_the_tool_has_one_vector_per_corner_and_alarms():
    # §3.5.3: a groove 4 wide, 10 deep, r = 3 inside it (G41 going down its left wall). Both bottom
    # corners are inner (one vector each): (13, -7) and (11, -7); the bottom move runs -x against +x.
    err = program_error("G10 L12 P1 R3\nG01 G41 D1 X10 F100\nY-10\nX14\nY0\nX30\nG40 X40\n")
    assert (err.code, err.alarm, err.line) == ("comp-interference", 41, 4)


def test_concave_depth_smaller_than_the_offset_alarms_although_nothing_is_overcut():
    # §3.5.3, the manual's own false positive: a dip 4 wide and 1 deep, r = 3 above it (G41 along
    # +x). The tool could pass over it at y = 3 without touching anything, but the bottom's corners are
    # inner, one vector each: down-then-+x gives x = 10 + 3 with y = -1 + 3, (13, 2); +x-then-up gives
    # x = 14 - 3, (11, 2). The bottom's move (13, 2) -> (11, 2) runs against +x: alarm 41 on it.
    err = program_error("G10 L12 P1 R3\nG00 X-10\nG01 G41 D1 X0 Y0 F100\nX10\nY-1\nX14\nY0\nX30\nG40 X40\n")
    assert (err.code, err.alarm, err.line) == ("comp-interference", 41, 6)


def test_a_corrected_helix_runs_as_a_straight_line_in_space():
    # The dip of test_dip_narrower_than_the_tool_is_bridged_by_a_straight_line as a helix (Z -2 over the
    # arc): compensation works in the plane only, so the corrected block is one straight move from
    # (10, 6, 0) to (20, 6, -2).
    text = "G10 L12 P1 R6\nG00 X-20\nG01 G41 D1 X-10 Y0 F100\nX10\nG03 X20 Y0 Z-2 I5 J0\nG01 X30\nG40 X40\n"
    corrected = [r for r in moves(text) if r["line"] == 5]
    assert len(corrected) == 1 and corrected[0]["kind"] == "line"
    assert close(corrected[0]["start"], (10, 6, 0)) and close(corrected[0]["end"], (20, 6, -2))


def test_pure_compensate_applies_the_same_correction():
    # The dip of test_dip_narrower_than_the_tool_is_bridged_by_a_straight_line through compensate(): the
    # start-up line, the +x line, the half circle, the +x line, the cancel line; the same tool path.
    elements = [
        PlaneElement((-20.0, 0.0), (-10.0, 0.0)),
        PlaneElement((-10.0, 0.0), (10.0, 0.0)),
        PlaneElement((10.0, 0.0), (20.0, 0.0), (15.0, 0.0), math.pi),
        PlaneElement((20.0, 0.0), (30.0, 0.0)),
        PlaneElement((30.0, 0.0), (40.0, 0.0)),
    ]
    out = compensate(elements, 6.0)
    assert [move.end for move in out] == [(-10.0, 6.0), (10.0, 6.0), (20.0, 6.0), (30.0, 6.0), (40.0, 0.0)]
    assert out[2].center is None and out[2].block == 2  # the arc runs as a line


# ------------------------------------------------------------------------------ property: random contours
_DIALECT = replace(get_dialect("gsk25i"), least_increment_mm=1e-6)
_ALLOWED = {"comp-interference", "comp-no-intersection", "comp-arc-centre"}


@st.composite
def contours(draw):
    """A random contour: lines and arcs with random turns at the joins (tangent joins now and then),
    lengths, radii and sweeps, including steps and arcs smaller than the offset."""
    n = draw(st.integers(2, 7))
    x, y, heading = 0.0, 0.0, 0.0
    blocks = []  # (text, kind, programmed direction or (centre, sweep))
    for _ in range(n):
        turn = draw(st.one_of(st.just(0.0), st.floats(-170.0, 170.0)))
        heading += math.radians(turn)
        if draw(st.booleans()):
            length = draw(st.floats(0.2, 15.0))
            x2, y2 = x + length * math.cos(heading), y + length * math.sin(heading)
            blocks.append((f"G01 X{x2:.6f} Y{y2:.6f}", "line", (x2 - x, y2 - y)))
        else:
            radius = draw(st.floats(0.3, 12.0))
            sweep = math.radians(draw(st.floats(15.0, 300.0))) * draw(st.sampled_from([1, -1]))
            side = 1.0 if sweep > 0 else -1.0  # the centre is to the left of travel for CCW
            cx, cy = x - side * radius * math.sin(heading), y + side * radius * math.cos(heading)
            a0 = math.atan2(y - cy, x - cx)
            x2, y2 = cx + radius * math.cos(a0 + sweep), cy + radius * math.sin(a0 + sweep)
            word = "G03" if sweep > 0 else "G02"
            arc_text = f"{word} X{x2:.6f} Y{y2:.6f} I{cx - x:.6f} J{cy - y:.6f}"
            blocks.append((arc_text, "arc", (x2 - x, y2 - y, sweep)))
            heading += sweep
        x, y = x2, y2
    return blocks


@success_share(0.15)
@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(contours(), st.sampled_from(["G41", "G42"]), st.floats(0.2, 6.0))
def test_random_contours_give_an_alarm_or_a_finite_path_without_interference(blocks, side, r):
    # Start-up from (-5, -5) to the contour's start (0, 0), the contour, cancel to (0, -20). Either one
    # of the compensation alarms (with its line), or a finite joined path in which no offset-mode block
    # still interferes after the correction: each block's own (last) move runs within 90° of its
    # programmed direction (a line, or an arc turned into a line: the chord), and an arc that stayed an
    # arc sweeps within 180° of its programmed sweep (checks (a) and (b)).
    first = 4  # program line of the first contour block
    header = [f"G10 L12 P1 R{r:.6f}", "G00 X-5 Y-5", f"G01 {side} D1 X0 Y0 F300"]
    text = "\n".join([*header, *(b[0] for b in blocks), "G01 G40 X0 Y-20"]) + "\n"
    try:
        toolpath = interpret(text, dialect=_DIALECT)
    except ProgramError as err:
        assert err.code in _ALLOWED and err.line >= first - 1, str(err)
        tally(False)
        return
    tally(True)
    assert np.all(np.isfinite(toolpath.start)) and np.all(np.isfinite(toolpath.end))
    assert np.allclose(toolpath.start[1:], toolpath.end[:-1], atol=1e-6)
    assert np.all(np.diff(toolpath.line) >= 0)
    for index, (_text, kind, programmed) in enumerate(blocks):
        rows = np.flatnonzero(toolpath.line == first + index)
        assert rows.size, "every contour block moves"
        last = rows[-1]
        if toolpath.kind[last] == SegmentKind.ARC:
            assert kind == "arc"
            assert abs(toolpath.sweep[last] - programmed[2]) <= math.pi + 1e-9
            continue
        move = toolpath.end[last, :2] - toolpath.start[last, :2]
        direction = np.array(programmed[:2])
        if np.linalg.norm(move) > 1e-9 and np.linalg.norm(direction) > 1e-9:
            assert float(move @ direction) >= -1e-9 * np.linalg.norm(move) * np.linalg.norm(direction)
