"""Hole patterns G120-G125, face milling G126/G127 and the pocket/boss cycles G110-G137 (dialects/gsk25i:
patterns.py, pockets.py), plus
a property test: random cycle blocks give a ProgramError or a finite tool path that keeps the level rules.

The pocket figures are lost (§3.4.16, examples X47-X54 are quality C): those tests check the
geometry the step lists fix (pocket wall = I, tool-centre radius I - r, layer depths W then Q to the
bottom, direction of the finishing arc, the transition arcs' direction) rather than a printed path.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from gcode_helpers import close, program_error, success_share, tally
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret
from cnc_gym.gcode.dialects.gsk25i import DIALECT
from cnc_gym.gcode.dialects.gsk25i.patterns import PATTERN_WORDS, pattern_holes, rectangle_holes
from cnc_gym.gcode.dialects.gsk25i.pockets import POCKET_WORDS, check_pocket, pocket_steps
from cnc_gym.toolpath import SegmentKind


def bottoms(tp) -> list[tuple[float, float]]:
    """XY of each feed move's end at its lowest Z: the holes drilled."""
    out = []
    for n in range(len(tp.kind)):
        if tp.kind[n] == SegmentKind.LINE and tp.end[n][2] < tp.start[n][2]:
            out.append((round(float(tp.end[n][0]), 6), round(float(tp.end[n][1]), 6)))
    return out


# ------------------------------------------------------------------ hole patterns
def test_g120_bolt_circle_drills_with_the_modal_cycle():
    """G120 X0 Y0 I50 J0. K4 with G81 stored (K0: data only; a Z or R word would drill, §3.4.3):
    holes at 0°, 90°, 180°, 270° on radius 50."""
    tp = interpret("G90 G99 G81 Z-5 R2 F100 K0;\nG120 X0 Y0 I50 J0. K4;\nG80;\n")
    assert close(sum(bottoms(tp), ()), (50, 0, 0, 50, -50, 0, 0, -50))


def test_g120_angle_without_decimal_point_is_thousandths_of_a_degree():
    a = bottoms(interpret("G99 G81 Z-5 R2 F100 K0;\nG120 X0 Y0 I10 J30000 K3;\n"))
    b = bottoms(interpret("G99 G81 Z-5 R2 F100 K0;\nG120 X0 Y0 I10 J30. K3;\n"))
    assert a == b and close(a[0], (10 * math.cos(math.radians(30)), 5.0))


def test_patterns_without_a_cycle_only_position():
    tp = interpret("G121 X10 Y0 I5 J90. K3;\n")
    assert all(tp.kind == SegmentKind.RAPID)
    assert close(tp.end[-1].tolist(), (10, 10, 0))


@pytest.mark.parametrize(("code", "kw", "expected"), [
    (121, {"i": -5.0, "j": 0.0, "k": 3}, [(0, 0), (-5, 0), (-10, 0)]),          # negative spacing: other way
    (122, {"i": 10.0, "j": 0.0, "p": 90.0, "k": 3}, [(10, 0), (0, 10), (-10, 0)]),
    (123, {"i": 5.0, "j": 2.0, "p": 3, "k": 2}, [(0, 0), (5, 0), (10, 0), (10, 2), (5, 2), (0, 2)]),
])  # fmt: skip
def test_pattern_positions(code, kw, expected):
    got = pattern_holes(code, 0.0, 0.0, **kw)
    assert close(sum(got, ()), sum(((float(x), float(y)) for x, y in expected), ()))


@pytest.mark.parametrize("text", ["G120 X0 Y0 I10 J0 K0;\n", "G121 X0 Y0 I10 J0;\n",
                                  "G122 X0 Y0 I5 J0 P10 K10000;\n"])
def test_pattern_hole_count_alarm(text):
    assert program_error(text).alarm == 225


def test_x63_g124_rectangle_drilling():
    """X63 (§3.6.5), our reading of the conflicting text (docs/gcode.md): X90 Y40 is the first corner
    (the example's prose), side 1 along +X of I40, side 2 of J10 turning right (G124 = CW); P3 holes on
    sides 1 and 3, K2 on sides 2 and 4, each side's holes from its first corner, length/n apart."""
    text = ("G90 G17 G0 X0 Y0 Z25 M03 F1000;\nG124 G81 X90 Y40 R5 Z-25 I40 J10 P3 K2 F800;\n"
            "G80 G0 X100 Y100 M05;\n")  # fmt: skip
    tp = interpret(text)
    third = 40 / 3
    expected = [(90, 40), (90 + third, 40), (90 + 2 * third, 40), (130, 40), (130, 35), (130, 30),
                (130 - third, 30), (130 - 2 * third, 30), (90, 30), (90, 35)]  # fmt: skip
    assert close(sum(bottoms(tp), ()), sum(((float(x), float(y)) for x, y in expected), ()))
    # Between holes back to R (Z5); after the last hole G98 (power-on) to the initial level Z25.
    assert close(float(tp.end[-2][2]), 25.0) and close(tp.end[-1].tolist(), (100, 100, 25))
    assert rectangle_holes(0, 0, 4, 2, 1, 1, ccw=True) == [(0, 0), (4, 0), (4, 2), (0, 2)]
    # P3 is a hole count here, not a dwell: G82 in G124 dwells only with P from an earlier block.
    tp = interpret("G124 G82 X0 Y0 R5 Z-5 I4 J2 P1 K1 F100;\n")
    assert not (tp.kind == SegmentKind.DWELL).any() and len(bottoms(tp)) == 4


def test_g124_needs_a_drilling_code_and_j():
    assert program_error("G124 X0 Y0 R5 Z-5 I4 J2 P1 K1 F10;\n").code == "cycle-argument"
    assert program_error("G124 G81 X0 Y0 R5 Z-5 I4 P1 K1 F10;\n").alarm == 216


def test_x64_g126_zigzag_face_milling():
    """X64 (§3.6.6): from X90 Y40 at Z-10 (R5), passes along +X of I70 stepping L10 over J30: four passes
    at Y40, 50, 60, 70 alternating direction; back up to R and the initial level Z25."""
    tp = interpret("G90 G17 G0 X0 Y0 Z25 M03 F1000;\nG126 X90 Y40 Z-10 R5 I70 J30 L10 F800;\nM30;\n")
    cuts = [(round(float(tp.end[n][0]), 6), round(float(tp.end[n][1]), 6)) for n in range(len(tp.kind))
            if tp.kind[n] == SegmentKind.LINE and tp.end[n][2] == -10]  # fmt: skip
    assert cuts == [(90, 40), (160, 40), (160, 50), (90, 50), (90, 60), (160, 60), (160, 70), (90, 70)]
    assert close(float(tp.end[-1][2]), 25.0)
    one_way = interpret("G90 G17 G0 X0 Y0 Z25 M03 F1000;\nG127 X90 Y40 Z-10 R5 I70 J30 L10 F800;\nM30;\n")
    passes = [n for n in range(len(one_way.kind)) if one_way.kind[n] == SegmentKind.LINE
              and one_way.end[n][2] == -10 and one_way.start[n][2] == -10]  # fmt: skip
    assert all(one_way.end[n][0] > one_way.start[n][0] for n in passes)  # every pass in +X


# ------------------------------------------------------------------ pockets (pure geometry, tool radius 5)
def _extent(steps, cx, cy):
    """Largest distance of the tool centre from (cx, cy) over all feed/arc ends and arc radii."""
    far = 0.0
    for step in steps:
        if step[0] in ("feed", "arc"):
            far = max(far, math.hypot(step[1][0] - cx, step[1][1] - cy))
        if step[0] == "arc":
            far = max(far, math.hypot(step[1][0] - step[2][0], step[1][1] - step[2][1])
                      + math.hypot(step[2][0] - cx, step[2][1] - cy))  # fmt: skip
    return far


def test_x47_g111_circular_pocket_roughing():
    """X47 (§3.4.16): I50 with D1 = 5: the tool centre reaches radius 45 (wall at 50); layers W20 below R5
    (-15), then Q10: -25, -35, -45, and the bottom -50; CW (G111) circles; rings 10, 20, 30, 40, 45."""
    steps = pocket_steps(111, 25, 25, 5, -50, 50, return_initial=False, feed=800, tool_radius=5, i=50,
                         l_step=10, w_first=20, q_step=10, v_clear=10)  # fmt: skip
    assert close(_extent(steps, 25, 25), 45.0)
    levels = sorted({s[1][2] for s in steps if s[0] == "arc"}, reverse=True)
    assert levels == [-15, -25, -35, -45, -50]
    arcs = [s for s in steps if s[0] == "arc"]
    assert all(s[3] < 0 for s in arcs)
    assert sorted({round(math.hypot(s[1][0] - 25, s[1][1] - 25), 6) for s in arcs}) == [10, 20, 30, 40, 45]
    # Steps (7)-(8): rapid to V10 above the previous level, then feed Q+V = 20 down.
    assert ("rapid", (25, 25, -5)) in steps and ("feed", (25, 25, -25), 800, False) in steps
    assert steps[-1] == ("rapid", (25, 25, 5))  # G99: back at R over the centre


@pytest.mark.parametrize(("code", "ccw_finish", "lead_sign"),
                         [(112, True, 1), (113, False, -1), (116, True, -1), (117, False, 1)])
def test_circular_finishing_directions(code, ccw_finish, lead_sign):
    """G112/G113 (inside) lead in with the finishing direction; G116/G117 (outside) against it (§3.4.19)."""
    j = 10 if code < 116 else 60
    steps = pocket_steps(code, 0, 0, 5, -50, 50, return_initial=True, feed=800, tool_radius=5, i=50, j=j)
    arcs = [s for s in steps if s[0] == "arc"]
    assert np.sign(arcs[0][3]) == lead_sign and np.sign(arcs[-1][3]) == lead_sign
    assert all((s[3] > 0) == ccw_finish for s in arcs[1:-1])
    path_radius = 45 if code < 116 else 55
    assert all(close(math.hypot(s[1][0], s[1][1]), path_radius) for s in arcs[1:-1])
    assert steps[-1] == ("rapid", (0, 0, 50))


@pytest.mark.parametrize(("code", "kw", "inner", "outer"), [
    (130, {"i": 70, "j": 50, "l_step": 5, "w_first": 20, "q_step": 10, "v_clear": 10, "u_corner": 10}, None,
     (30, 20)),
    (132, {"i": 80, "j": 50, "l_step": 30, "u_corner": 10}, None, (35, 20)),
    (136, {"i": 80, "j": 50, "l_step": 30, "u_corner": 5}, (45, 30), None),
    (134, {"i": 80, "j": 50, "l_step": 2, "w_first": 10, "q_step": 5, "v_clear": 10, "u_corner": 5,
           "e_stock": 3}, (45, 30), None),
])  # fmt: skip
def test_rectangular_cycles_keep_the_tool_on_the_right_side_of_the_wall(code, kw, inner, outer):
    """X51-X54 with D1 = 5: pocket cycles never take the tool centre beyond half-width - 5 (the tool
    edge stays inside I x J); boss cycles never come closer than half-width + 5 (the edge stays outside)."""
    steps = pocket_steps(code, 0, 0, 5, -50, 50, return_initial=False, feed=800, tool_radius=5, **kw)
    cut = [s for s in steps if s[0] in ("feed", "arc") and s[1][2] < 5]
    xs = [abs(s[1][0]) for s in cut]
    ys = [abs(s[1][1]) for s in cut]
    if outer is not None:
        assert max(xs) <= outer[0] + 1e-9 and max(ys) <= outer[1] + 1e-9
        assert close(max(xs), outer[0]) and close(max(ys), outer[1])
    else:
        # Every point of the finishing loop lies outside the boss grown by the tool radius.
        loop = [s for s in cut if s[1][2] == -50 and s[0] == "feed" and abs(s[1][0]) <= inner[0] + 1e-9
                and abs(s[1][1]) <= inner[1] + 1e-9]  # fmt: skip
        assert all(abs(s[1][0]) >= inner[0] - 1e-9 or abs(s[1][1]) >= inner[1] - 1e-9 for s in loop)


@pytest.mark.parametrize(("code", "kw", "alarm"), [
    (110, {"i": None}, 215), (110, {"w_first": 0}, 217), (110, {"q_step": None}, 218),
    (110, {"l_step": 12}, 219), (110, {"v_clear": -1}, 220), (110, {"i": 4}, 222),
    (132, {"u_corner": 0}, 211), (130, {"u_corner": -1}, 224), (130, {"u_corner": 30}, 210),
    (112, {"j": 48}, 212), (134, {"e_stock": None}, 228), (134, {"e_stock": 0.5}, 226),
    (132, {"l_step": 3}, 213), (130, {"j": None}, 216),
])  # fmt: skip
def test_special_cycle_alarms(code, kw, alarm):
    args = {"tool_radius": 5.0, "i": 50.0, "j": 40.0, "l_step": 8.0, "w_first": 10.0, "q_step": 5.0,
            "v_clear": 2.0, "u_corner": 6.0, "e_stock": 2.0}  # fmt: skip
    args.update(kw)
    problem = check_pocket(code, **args)
    assert problem is not None and problem[1] == alarm


def test_pocket_cycle_in_a_program_with_d0_and_plane_rule():
    """D0 = tool radius 0 (§3.4.16): G112 finishes on radius I itself; G110-G137 only in G17 (alarm 227);
    D missing is alarm 221."""
    tp = interpret("G90 G00 X50 Y50 Z50;\nG99 G112 X25 Y25 R5 Z-50 I50 J10 F800 D0;\nG80 X50 Y50 Z50;\n"
                   "M30;\n")
    arcs = [n for n in range(len(tp.kind)) if tp.kind[n] == SegmentKind.ARC]
    assert close(float(tp.radius[arcs[1]]), 50.0)
    assert program_error("G18 G112 X25 Y25 R5 Z-50 I50 J10 F800 D0;\n").alarm == 227
    assert program_error("G112 X25 Y25 R5 Z-50 I50 J10 F800;\n").alarm == 221


# ------------------------------------------------------------------ property: random cycle blocks
_CODES = ["G73", "G74", "G76", "G81", "G82", "G83", "G84", "G85", "G86", "G87", "G88", "G89"]
_num = st.one_of(st.integers(-60, 60).map(str), st.floats(-60, 60, allow_nan=False).map(lambda v: f"{v:.3f}"))


#: P2011, G83's clearance d (GSK 25i standard setting).
G83_CLEARANCE = DIALECT.cycle_params.g83_clearance_mm


def test_g83_re_approaches_to_d_above_the_depth_already_cut_after_each_return_to_r():
    """§3.4.7 (and the Fanuc 0i's G83, d = parameter 5115): "in the second and subsequent cutting feeds,
    rapid traverse is performed up to a d point just before where the last drilling ended". The return
    between pecks goes up to R, and the next rapid goes down to d above the last peck's depth, so with
    R = 0, Q1 and d = 0.5 it ends at -0.5, below R: the case hypothesis once found against a test that
    forgot the depth already cut when the tool came back up to R."""
    tp = interpret("M3 S100;\nG00 Z0;\nG98 G90 G83 X0 Y0 Z-2 R0 Q1 F1;\nG80;\n")
    path = [(int(tp.kind[n]), round(float(tp.end[n][2]), 9)) for n in range(len(tp.kind))]
    feed, rapid = int(SegmentKind.LINE), int(SegmentKind.RAPID)
    assert path == [(feed, -1.0), (rapid, 0.0), (rapid, -1.0 + G83_CLEARANCE), (feed, -2.0), (rapid, 0.0)]


@success_share(0.08)
@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(code=st.sampled_from(_CODES), ret=st.sampled_from(["G98", "G99"]),
       dist=st.sampled_from(["G90", "G91"]), start_z=st.integers(-20, 60),
       words=st.dictionaries(st.sampled_from("XYZRQPKF"), _num, max_size=8),
       more=st.lists(st.dictionaries(st.sampled_from("XYZRQ"), _num, max_size=3), max_size=3))  # fmt: skip
@example(code="G83", ret="G98", dist="G90", start_z=0,
         words={"X": "0", "Y": "0", "Z": "-2", "R": "0", "Q": "1", "F": "1"}, more=[])  # fmt: skip
def test_random_cycle_blocks_give_an_error_or_a_path_that_keeps_the_levels(code, ret, dist, start_z, words,
                                                                           more):  # fmt: skip
    """Any cycle block: a ProgramError, or a finite path where no move goes below the hole
    bottom, feeds stay between R and the bottom, and a downward rapid never ends below R except in
    G83's re-approach, which ends at least d (P2011) above the deepest point already cut at that hole
    (the return to R between pecks does not undo the cut: §3.4.7), and G87's drop to R under the part."""
    if "P" in words:
        words["P"] = str(abs(int(float(words["P"]))))
    if "K" in words:
        words["K"] = str(int(float(words["K"])) % 4)
    block = " ".join(f"{k}{v}" for k, v in words.items())
    later = "".join(" ".join(f"{k}{v}" for k, v in w.items()) + ";\n" for w in more if w)
    text = f"M3 S100;\nG00 Z{start_z};\n{dist} {ret} {code} {block};\n{later}G80;\n"
    try:
        tp = interpret(text)
    except ProgramError:
        tally(False)
        return
    tally(True)
    assert np.isfinite(tp.end).all() and np.isfinite(tp.start).all()
    if "R" not in words or "Z" not in words or code == "G87" or any("Z" in w or "R" in w for w in more):
        return  # the level rule below needs the levels of the first block for the whole run
    r, bottom = float(words["R"]), float(words["Z"])
    if dist == "G91":  # R from the initial level, Z from R (§3.4)
        r = start_z + r
        bottom = r + bottom
    if start_z < r:
        return  # an initial level below R: G98 returns down to it by definition (no level rule to check)
    top = max(start_z, r)
    cut: dict[tuple[float, float], float] = {}  # hole position → the deepest point cut there
    for n in range(len(tp.kind)):
        if tp.line[n] < 3:
            continue  # the setup rapid to the initial level
        z0, z1 = float(tp.start[n][2]), float(tp.end[n][2])
        hole = (round(float(tp.end[n][0]), 6), round(float(tp.end[n][1]), 6))
        assert z1 >= bottom - 1e-6 and z1 <= top + 1e-6
        if tp.kind[n] == SegmentKind.LINE:
            assert bottom - 1e-6 <= min(z0, z1) and max(z0, z1) <= r + 1e-6
            cut[hole] = min(cut.get(hole, r), z1)
        elif tp.kind[n] == SegmentKind.RAPID and z1 < z0 - 1e-9 and z1 < r - 1e-6:
            assert code == "G83" and z1 >= cut.get(hole, r) + G83_CLEARANCE - 1e-6


# ------------------------------------------------------------------ X47-X54 as programs (D1 = 5)
@pytest.mark.parametrize(("block", "reach"), [
    # (example block, expected farthest tool-centre point from the centre (25, 25) while below R, |dx|, |dy|)
    ("G99 G111 X25 Y25 R5 Z-50 I50 W20 Q10 L10 V10 F800 D1", (45, 45)),   # X47: circle radius I - r
    ("G99 G112 X25 Y25 R5 Z-50 I50 J10 F800 D1", (45, 45)),               # X48: finish radius I - r
    # X49: plunges outside the stock at J + r = 105 on +X; the first ring is one step in (95).
    ("G99 G114 X25 Y25 R5 Z-50 I50 J100 W20 Q10 L10 V10 F800 D1", (105, 95)),
    ("G99 G116 X25 Y25 R5 Z-50 I50 J60 F800 D1", (60, 55)),               # X50: start J60, circle I + r
    ("G99 G130 X25 Y25 R5 Z-50 I70 J50 W20 Q10 L5 V10 U10 F800 D1", (30, 20)),  # X51: I/2 - r, J/2 - r
    ("G132 X25 Y25 R5 Z-50 I80 J50 L30 U10 F800 D1", (35, 20)),           # X52
    # X53: plunges at I/2 + r + (E-1)·max(I, J)/2 = 125 on +X; the first ring is L2 in: J/2 + r + 78.
    ("G99 G134 X25 Y25 R5 Z-50 I80 J50 W10 Q5 V10 L2 E3 U5 F800 D1", (125, 108)),
    ("G99 G136 X25 Y25 R5 Z-50 I80 J50 L30 U5 F800 D1", (70, 30)),        # X54: start L30 outside, J/2 + r
])  # fmt: skip
def test_x47_x54_special_cycle_examples(block, reach):
    """The manual's examples (§3.4.16-§3.4.23; the paths are our design: quality C in docs/gsk25i_examples.md)
    run with D1 = 5: cut to the bottom Z-50, never beyond the reach the example's numbers give, back over the
    centre at R (G99; G132's block has no G98/G99 and returns to the power-on G98 initial level Z50), then
    G80's move to X50 Y50 Z50."""
    text = f"G90 G00 X50 Y50 Z50;\n{block};\nG80 X50 Y50 Z50;\nM30;\n"
    tp = interpret(text, tool_offsets={"D": {1: 5.0}})
    below = tp.end[:, 2] < 5 - 1e-9
    assert close(float(tp.end[:, 2].min()), -50.0)
    dx = np.abs(tp.end[below, 0] - 25).max()
    dy = np.abs(tp.end[below, 1] - 25).max()
    arcs = tp.kind == SegmentKind.ARC
    if arcs.any():  # an arc's extreme can lie between its ends: the radius about its centre bounds it
        dx = max(dx, float(np.max(np.abs(tp.center[arcs, 0] - 25) + tp.radius[arcs])))
        dy = max(dy, float(np.max(np.abs(tp.center[arcs, 1] - 25) + tp.radius[arcs])))
    assert close(dx, reach[0]) and close(dy, reach[1])
    back = 50.0 if "G132" in block else 5.0
    assert close(tp.end[-2].tolist(), (25, 25, back)) and close(tp.end[-1].tolist(), (50, 50, 50))


_SPECIAL = [f"G{n}" for n in (*range(110, 118), *range(130, 138))]
_PATTERN = [f"G{n}" for n in range(120, 128)]
_small = st.one_of(st.integers(-5, 60).map(str), st.floats(-5, 60, allow_nan=False).map(lambda v: f"{v:.2f}"))


@success_share(0.03)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(code=st.sampled_from(_SPECIAL + _PATTERN), drill=st.sampled_from(["", "G81 Z-3 R1 F100 K0;\n"]),
       words=st.dictionaries(st.sampled_from("XYZRIJLWQVUEKPD"), _small, max_size=12))  # fmt: skip
def test_random_special_and_pattern_blocks_give_an_error_or_a_finite_path(code, drill, words):
    """Pocket, boss, pattern and face-milling blocks with random words: a ProgramError, or a finite path
    that stays within the bottom and the start height (D1 = 4)."""
    number = int(code[1:])
    allowed = set("XYZ") | set(POCKET_WORDS.get(number, "") or PATTERN_WORDS[number])
    words = {k: v for k, v in words.items() if k in allowed}  # mostly well-formed: reach the geometry
    for letter in "LKPD":
        if letter in words:
            words[letter] = str(abs(int(float(words[letter]))))
    if "D" in words:
        words["D"] = str(int(words["D"]) % 3)
    block = " ".join(f"{k}{v}" for k, v in words.items())
    text = f"G00 Z60 F200;\n{drill}{code} {block};\nG80;\n"
    try:
        tp = interpret(text, tool_offsets={"D": {1: 4.0, 2: 1.5}})
    except ProgramError:
        tally(False)
        return
    tally(True)
    assert np.isfinite(tp.end).all() and np.isfinite(tp.start).all()
    assert np.isfinite(tp.radius).all() and np.isfinite(tp.sweep).all()
    assert tp.end[:, 2].max() <= 60 + 1e-6
    if "Z" in words and code in _SPECIAL:
        assert tp.end[:, 2].min() >= min(float(words["Z"]), -3.0) - 1e-6


def test_pattern_origin_follows_g91_and_radius_must_be_positive():
    """X, Y of a pattern are absolute in G90 and from the current position in G91 (§3.5.7); G120's radius
    must be positive (alarm 215, ours: "represented by the positive number")."""
    a = interpret("G00 X10 Y10;\nG91 G121 X5 Y0 I2 J0. K2;\n")
    assert close(a.end[-1].tolist(), (17, 10, 0))
    assert program_error("G120 X0 Y0 I-5 J0 K3;\n").alarm == 215


def test_special_cycle_while_a_drilling_cycle_is_modal_is_alarm_214():
    err = program_error("G81 X0 Y0 Z-5 R1 F100;\nG112 X25 Y25 R5 Z-50 I50 J10 D0;\n")
    assert err.alarm == 214 and err.line == 2
    interpret("G81 X0 Y0 Z-5 R1 F100;\nG80;\nG112 X25 Y25 R5 Z-50 I50 J10 D0;\n")  # after G80: fine
