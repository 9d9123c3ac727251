"""The Syntec 8.20 dialect's rules one by one (docs/syntec.md): reading, units and feed, modes and
smoothing, canned cycles and hole patterns, coordinates and transforms, calls, tool length measurement.
Expected values are worked out by hand in each test."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.gcode import get_dialect, interpret, read_program
from cnc_gym.gcode.dialects.syntec.options import SyntecOptions
from cnc_gym.gcode.interpreter import Interpreter
from cnc_gym.toolpath import SegmentMode

SYNTEC = get_dialect("syntec")


def variant(**options):
    return replace(SYNTEC, options=replace(SYNTEC.options, **options))


def run(text: str, dialect=SYNTEC, **kw):
    return interpret(text, dialect=dialect, **kw)


def ends(text: str, **kw) -> list[list[float]]:
    return [r["end"] for r in run(text, **kw).to_records() if r["kind"] != "dwell"]


def error(text: str, **kw) -> ProgramError:
    with pytest.raises(ProgramError) as info:
        run(text, **kw)
    return info.value


# ---------------------------------------------------------------------- reading
def test_double_slash_comments_anywhere_outside_parentheses():
    text = ("// a whole-line comment (with a lone '(' and a ';')\nG01 X1. F100 //after a block; G00 X9\n"
            "(G01 X7. //inside a parenthesis comment)\nG01 Y2.; // after the end of block\n")  # fmt: skip
    assert ends(text) == [[1.0, 0.0, 0.0], [1.0, 2.0, 0.0]]
    assert [b.line for b in read_program(text, dialect="syntec").blocks] == [2, 4]


def test_spaces_inside_words_and_leading_zeros_of_codes():
    assert ends("G1 X -0.005 F2000\nG01 X-0.010\n") == [[-0.005, 0.0, 0.0], [-0.01, 0.0, 0.0]]
    assert run("G5.1 Q1 E0.01\nG01 X1. F100\n").smoothing_tolerance_mm.tolist() == [0.01]


def test_whole_numbers_are_least_units_of_the_unit_in_force():
    """X1000 is 1 mm in G71 and 0.1 inch = 2.54 mm in G70 (LIU 0.0001 inch), whichever comes first: the
    reader cannot know, the block reads it when it runs. F is never scaled."""
    assert ends("G01 X1000 F100\n") == [[1.0, 0.0, 0.0]]
    assert ends("G70\nG01 X1000 F10.\n") == [[2.54, 0.0, 0.0]]
    assert ends("G01 X1000 F100\n", units="inch") == [[2.54, 0.0, 0.0]]
    assert run("G01 X1. F1000\n").feed.tolist() == [1000.0]


def test_literals_finer_than_the_unit_are_rounded_to_it():
    """G71 rounds to 1 µm, G70 to 0.0001 inch (no truncation at read time: the unit is known only when
    the block runs)."""
    assert ends("G01 X1.2345 F100\n") == [[1.235, 0.0, 0.0]]
    assert math.isclose(ends("G70 G01 X1.2345 F10.\n")[0][0], 1.2345 * 25.4, abs_tol=1e-9)


def test_typos_of_the_manual_are_errors_not_guesses():
    assert error("G03 X50. Y80.793. R50.\n").code == "bad-number"  # double decimal point
    assert error("G01 X50. Y9.207 R8.\n").code == "unused-word"  # R on a line is no corner radius


# ---------------------------------------------------------------------- units and feed
def test_default_feed_in_each_mode_and_unit():
    assert run("G01 X1.\n").feed.tolist() == [1000.0]  # G94: 1000 mm/min
    assert run("G70 G01 X1.\n").feed.tolist() == [25400.0]  # 1000 inch/min
    assert run("S200 M03\nG95 G01 X1.\n").feed.tolist() == [200.0]  # G95: 1 mm/rev × 200
    assert run("G95 G01 X1. F0.5 S100 M03\nG94 G01 X2.\n").feed.tolist() == [50.0, 1000.0]
    assert run("G01 X1. F300\nG70\nG01 X2.\n").feed.tolist() == [300.0, 300.0]  # an F is kept


def test_units_switch_in_the_middle_of_a_program():
    """G70/G71 convert work offsets and tool data automatically (§G70/G71): a switch is allowed anywhere;
    offsets are kept in mm."""
    assert ends("G01 X1. F100\nG70\nX1.\nG71\nX1.\n") == [[1.0, 0, 0], [25.4, 0, 0], [1.0, 0, 0]]
    assert error("G20\n").code == "unknown-code" and error("G21\n").code == "unknown-code"


def test_g04_decimal_p_option_refuses_it():
    assert error("G04 P2.5\n", dialect=variant(g04_p_decimal="error")).code == "decimal-point-not-allowed"
    assert run("G04 P2500\n", dialect=variant(g04_p_decimal="error")).dwell_s.tolist() == [2.5]
    assert error("G04 X10000.\n").code == "bad-dwell"  # 0.001-9999.999 s


def test_options_are_checked():
    with pytest.raises(ConfigError):
        SyntecOptions(peck_tapping_type=2)
    with pytest.raises(ConfigError):
        SyntecOptions(g04_p_decimal="ms")
    with pytest.raises(ConfigError):
        SyntecOptions(hshp_tolerance_mm={7: 0.01})


# ---------------------------------------------------------------------- cutting modes, G05, G05.1
def test_cutting_modes_g61_to_g64():
    tp = run("G61 G01 X1. F100\nG62 X2.\nG63 X3.\nG64 X4.\nG09 X5.\n")
    modes = [SegmentMode(int(m)) for m in tp.modes]
    assert modes == [SegmentMode.EXACT_STOP, SegmentMode.NONE,
                     SegmentMode.OVERRIDE_LOCKED | SegmentMode.TAPPING_MODE, SegmentMode.NONE,
                     SegmentMode.EXACT_STOP]  # fmt: skip


def test_g05_parameter_sets_and_its_rules():
    for p in (10000, 1, 5):
        tp = run(f"G05 P{p}\nG01 X1. F100\nG02 X2. R.5\nG00 X3.\nG05 P0\nG01 X4.\n",
                 dialect=variant(hshp_tolerance_mm={10000: 0.01, 1: 0.02, 5: 0.005}))
        expected = {10000: 0.01, 1: 0.02, 5: 0.005}[p]
        assert tp.smoothing_tolerance_mm.tolist() == [expected] * 3 + [0.0]
    assert error("G05 P7\n").code == "bad-g05"
    assert error("G05\n").code == "bad-g05"
    assert error("G05 P10000 X1.\n").code == "bad-g05"
    assert error("G05 P10000\nM03\n").code == "hshp-m-code"
    assert error("G05 P10000\nG41 D1\nG05 P0\n").code == "hshp-compensation"
    assert error("G05 P10000\nG01 X1. F100\n").code == "hshp-no-end"
    run("G05 P10000\nG01 X1. F100\nM30\n")  # M30 may end the program in G05
    assert error("G06.2 P3 K0 X0 Y0 Z0\n").code == "nurbs-outside-hpcc"


def test_g05_1_without_q_or_e_is_ineffective_with_a_note():
    """§G05.1 description 1: "If command is inadequate (ex: Q or E unspecified), it will be ineffective":
    the block changes nothing (smoothing stays off, or stays at the tolerance in force), and the tool path
    carries a note naming the block."""
    for text in ("G05.1 Q1\nG01 X1. F100\n", "G05.1 E0.01\nG01 X1. F100\n"):
        tp = run(text)
        assert tp.smoothing_tolerance_mm.tolist() == [0.0]
        assert len(tp.notices) == 1 and tp.notices[0].startswith("<program>:1: note: G05.1")
        assert tp.notices[0].endswith("[smoothing-ineffective]")
    kept = run("G05.1 Q1 E0.01\nG01 X1. F100\nG05.1 Q1\nG01 X2.\n")
    assert kept.smoothing_tolerance_mm.tolist() == [0.01, 0.01]
    assert kept.notices[0].startswith("<program>:3: note:")


def test_g05_1_smoothing_rules():
    assert error("G05.1 Q1 E0\n").code == "bad-smoothing"
    assert error("G61\nG05.1 Q1 E0.01\n").code == "smoothing-in-exact-stop"
    assert error("G63\nG05.1 Q1 E0.01\n").code == "smoothing-in-exact-stop"
    # only G01 rows; E in inch in G70; G54 and G92 also skip the next G01
    tp = run("G70\nG05.1 Q1 E0.001\nG01 X1. F10.\nG02 X2. R.5\nG00 X3.\nG54\nG01 X4.\nX5.\nG92 X0\nX1.\n"
             "G05.1 Q0\nX2.\n")  # fmt: skip
    assert tp.smoothing_tolerance_mm.tolist() == [pytest.approx(0.0254), 0, 0, 0, pytest.approx(0.0254), 0, 0]


def test_smoothing_tolerance_reaches_the_controller():
    # G05.1 Q1 E0.05 on a polyline of short G01 blocks: the controller blends the corners within E.
    from cnc_gym.machine import load_machine
    from cnc_gym.motion import Controller

    text = "G05.1 Q1 E0.05\nG01 X1. Y0.2 F600\nX2. Y0.\nX3. Y0.2\nX4. Y0.\nG05.1 Q0\n"
    tp = run(text)
    assert tp.smoothing_tolerance_mm.tolist() == [0.05, 0.05, 0.05, 0.05]
    chunk = Controller(tp, load_machine("vmc-small"), in_position_check=False).run_to_end()
    corners = [(1, 0.2, 0), (2, 0, 0), (3, 0.2, 0)]
    gap = [np.min(np.linalg.norm(chunk.position - c, axis=1)) for c in corners]
    assert min(gap) > 0.01 and max(gap) <= 0.05 + 1e-9


def test_nurbs_without_f_takes_the_previous_curve_feed():
    curve = "G06.2 P3 K0 X{x}. Y{y}. Z0\nK0 X{x}. Y{y1}. Z0\nK0 X{x1}. Y{y1}. Z0\nK1.\nK1.\nK1.\n"
    text = ("G05 P10000\n" + curve.format(x=0, x1=5, y=0, y1=5).replace("Z0\nK0", "Z0 F5000.\nK0", 1)
            + "G01 X6. F100\n" + curve.format(x=6, x1=11, y=5, y1=10) + "G05 P0\n")  # fmt: skip
    assert run(text).feed.tolist() == [5000.0, 100.0, 5000.0]


def test_knot_without_decimal_point_is_a_plain_number():
    text = "G05 P10000\nG06.2 P3 K0 X0 Y0 Z0 F100\nK0 X0 Y5. Z0\nK0 X5. Y5. Z0\nK1\nK1\nK1\nG05 P0\n"
    assert run(text).nurbs[0].knots.tolist() == [0, 0, 0, 1, 1, 1]


# ---------------------------------------------------------------------- G33, G96/G97
def test_g33_lead_and_spindle_limits():
    tp = run("S400 M03\nG33 Z-10. F2.\nZ-20.\nG01 X1.\n")
    assert tp.feed.tolist() == [800.0, 800.0, 1000.0]  # F2. is the lead, not the modal feed
    assert error("G33 Z-10. F2.\n").code == "thread-speed"  # S0
    assert error("S10000 M03\nG33 Z-10. F2.\n").code == "thread-speed"  # 2 × 10000 > 15000 mm/min
    assert error("S100 M03\nG33 Z-10.\n").code == "missing-feed"


def test_g96_needs_a_tool_diameter_and_g97_ends_it():
    assert error("G96 S130 M03\n").code == "css-no-diameter"
    tp = run("D1\nG96 S100 M03\nG01 X1. F100\nG97 S700\nX2.\n", tool_offsets={"D": {1: 5.0}})
    assert tp.spindle_rpm[0] == pytest.approx(1000 * 100 / (math.pi * 10)) and tp.spindle_rpm[1] == 700.0
    feet = run("G70\nD1\nG96 S100 M03\nG01 X1. F10.\n", tool_offsets={"D": {1: 5.0}})
    assert feet.spindle_rpm[0] == pytest.approx(1000 * 30.48 / (math.pi * 10))  # 100 ft/min


# ---------------------------------------------------------------------- canned cycles
HEAD = "F1000. S500\nM03\nG00 X0. Y0. Z10.\nG90 G99\n"


def feeds(text: str, **kw) -> list[tuple[float, float]]:
    tp = run(text, **kw)
    return [(round(float(tp.end[i][2]), 6), float(tp.feed[i])) for i in range(len(tp)) if tp.kind[i] == 1]


def test_cycle_dwell_p_seconds_or_ms():
    assert [d for d in run(HEAD + "G82 X5. Y5. Z-10. R-5. P2500\n").dwell_s if d] == [2.5]
    assert [d for d in run(HEAD + "G82 X5. Y5. Z-10. R-5. P1.5\n").dwell_s if d] == [1.5]


def test_r_and_q_are_stored_only_by_a_drilling_block():
    """R alone does not drill (no axis word) and is not stored: the holes keep R-5."""
    tp = run(HEAD + "G83 X5. Y5. Z-10. R-5. Q3.\nR-1. Q1.\nX15.\n")
    starts = [float(tp.start[i][2]) for i in range(len(tp)) if tp.kind[i] == 1]
    assert starts == [-5.0, -7.5, -5.0, -7.5]  # both holes: R-5, one peck of Q3 and the rest


def test_k_counts_and_range():
    tp = run(HEAD + "G91 G81 X10. Z-5. R-15. K3\n")
    holes = [tuple(round(float(c), 6) for c in tp.end[i][:2]) for i in range(len(tp)) if tp.kind[i] == 1]
    assert holes == [(10.0, 0.0), (20.0, 0.0), (30.0, 0.0)]
    assert error(HEAD + "G81 X5. Z-10. R-5. K10000\n").code == "bad-cycle"


def test_group_01_code_in_a_cycle_block_is_refused():
    assert error(HEAD + "G01 G81 X5. Z-10. R-5.\n").code == "cycle-group01"


def test_drilling_axis_follows_the_plane():
    """G18: the drilling axis is Y (§canned cycles: G17 Z, G18 Y, G19 X)."""
    tp = run("F100\nG00 X0 Y10. Z0\nG18 G81 X5. Z5. Y-10. R5.\n")
    line = next(i for i in range(len(tp)) if tp.kind[i] == 1)
    assert tp.start[line].tolist() == [5.0, 5.0, 5.0] and tp.end[line].tolist() == [5.0, -10.0, 5.0]


def test_peck_tapping_types():
    """G84 with Q3 from R-5 to Z-10 (d = 0.5): type III (Pr4001 = 0) back to R after each peck, type II
    (Pr4001 = 1) back up by d."""
    text = HEAD + "G84 X5. Y5. Z-10. R-5. Q3.\n"
    assert feeds(text) == [(-8.0, 1000.0), (-5.0, 1000.0), (-10.0, 1000.0), (-5.0, 1000.0)]
    assert feeds(text, dialect=variant(peck_tapping_type=1)) == [
        (-8.0, 1000.0), (-7.5, 1000.0), (-10.0, 1000.0), (-5.0, 1000.0)]


def test_q_is_shared_between_peck_and_tapping_cycles():
    text = HEAD + "G83 X5. Y5. Z-10. R-5. Q3.\nG84 X15.\n"
    assert feeds(text)[-4:] == [(-8.0, 1000.0), (-5.0, 1000.0), (-10.0, 1000.0), (-5.0, 1000.0)]


def test_tapping_reverses_the_spindle_at_the_bottom_and_at_r():
    tp = run("F1000. S500\nM04\nG00 X0. Y0. Z10.\nG99 G74 X5. Y5. Z-10. R-5.\nG01 X6.\n")
    # G00 Z10, rapid to the hole, rapid to R, in CCW, out CW (reversed at the bottom), the next move CCW
    assert tp.spindle_rpm.tolist() == [-500.0, -500.0, -500.0, -500.0, 500.0, -500.0]


# ---------------------------------------------------------------------- hole patterns
PATTERN_HEAD = "G90 G81 Z-5. R1. F100 K0\n"


def pattern_holes(text: str) -> list[tuple[float, float]]:
    tp = run(text)
    return [(round(float(tp.end[i][0]), 3) + 0.0, round(float(tp.end[i][1]), 3) + 0.0)
            for i in range(len(tp)) if tp.kind[i] == 1]  # fmt: skip


def test_bolt_circle_direction_follows_the_sign_of_k():
    ccw = pattern_holes(PATTERN_HEAD + "G134 X0 Y0 I10. J0 K4\n")
    cw = pattern_holes(PATTERN_HEAD + "G134 X0 Y0 I10. J0 K-4\n")
    assert ccw == [(10.0, 0.0), (0.0, 10.0), (-10.0, 0.0), (0.0, -10.0)]
    assert cw == [(10.0, 0.0), (0.0, -10.0), (-10.0, 0.0), (0.0, 10.0)]
    assert error(PATTERN_HEAD + "G134 X0 Y0 I10. J0 K0\n").code == "cycle-argument"
    assert error(PATTERN_HEAD + "G134 X0 Y0 I-10. J0 K4\n").code == "cycle-argument"


def test_line_with_a_negative_spacing_goes_the_other_way():
    holes = pattern_holes(PATTERN_HEAD + "G135 X0 Y0 I-10. J0 K3\n")
    assert holes == [(0.0, 0.0), (-10.0, 0.0), (-20.0, 0.0)]


def test_arc_angles_with_and_without_a_decimal_point():
    with_point = pattern_holes(PATTERN_HEAD + "G136 X0 Y0 I10. J90. P90. K2\n")
    without = pattern_holes(PATTERN_HEAD + "G136 X0 Y0 I10. J90000 P90000 K2\n")
    assert with_point == without == [(0.0, 10.0), (-10.0, 0.0)]


def test_patterns_need_a_stored_cycle_and_their_own_block():
    assert error("G134 X0 Y0 I10. J0 K4\n").code == "pattern-no-cycle"
    assert error("G81 G134 X0 Y0 I10. J0 K4 Z-5. R1. F100\n").code == "cycle-conflict"
    assert error(PATTERN_HEAD + "G137.1 X0 Y0 I10. J10. K2\n").code == "cycle-argument"  # no P


# ---------------------------------------------------------------------- coordinates and transforms
def test_fifteen_work_systems():
    """G59.1-G59.9 select work systems 7-15 (offsets set on the controller's screens: set here in the
    interpreter's offset memory)."""
    program = read_program("G59.3 G01 X1. F100\nG59.9 X1.\nG54 X1.\n", dialect="syntec")
    core = Interpreter(program, SYNTEC)
    core.state.offsets.wcs[8] = [100.0, 0.0, 0.0]  # G59.3: the 9th system
    core.state.offsets.wcs[14] = [200.0, 0.0, 0.0]  # G59.9: the 15th
    tp = core.run()
    assert tp.end[:, 0].tolist() == [101.0, 201.0, 1.0]
    assert error("G54.1 P1\n").code == "unknown-code"


def test_g10_writes_tool_offsets_only():
    tp = run("G10 L10 P1 R5.\nG91 G10 L11 P1 R.5\nG90 G43 H1 G01 Z0 F100\n")
    assert tp.end[0].tolist() == [0.0, 0.0, 5.5]
    tp = run("G10 L12 P1 R5.\nG10 L13 P1 R-1.\nG41 D1 G01 X10. F100\nY10.\nX20.\nG40 X30.\n")
    assert tp.end[0].tolist() == [6.0, 4.0, 0.0]  # D1 = 5 - 1: the inner corner of y = 4 and x = 10 - 4
    for kind in ("L2", "L20", "L50", ""):
        assert error(f"G10 {kind} P1 X5.\n").code == "bad-g10"


def test_g30_p1_is_the_machine_origin_and_p2_the_default():
    machine_text = "G00 X5. Y5.\nG30 X10.\nG00 X5.\nG30 P1 X10.\n"
    assert [e[0] for e in ends(machine_text)] == [5.0, 10.0, 0.0, 5.0, 10.0, 0.0]
    assert error("G30 P5 X1.\n").code == "bad-reference"


def test_polar_angle_sign_option_and_incremental_radius():
    assert ends("G16\nG00 X10. Y90.\n") == [[0.0, 10.0, 0.0]]
    assert ends("G16\nG00 X10. Y90.\n", dialect=variant(polar_angle_cw=True)) == [[0.0, -10.0, 0.0]]
    # G91: the radius adds to the last radius about the same origin (the text); Fanuc: origin at the tool
    syntec = ends("G16\nG00 X10. Y0\nG91 X5.\n")
    fanuc = ends("G16\nG00 X10. Y0\nG91 X5.\n", dialect=variant(polar_incremental_origin_at_tool=True))
    assert syntec[-1] == [15.0, 0.0, 0.0] and fanuc[-1] == [15.0, 0.0, 0.0]
    syntec = ends("G16\nG00 X10. Y90.\nG91 X5. Y-90.\n")
    fanuc = ends("G16\nG00 X10. Y90.\nG91 X5. Y-90.\n",
                 dialect=variant(polar_incremental_origin_at_tool=True))
    assert [round(c, 9) for c in syntec[-1]] == [15.0, 0.0, 0.0]  # 15 at 0° about the origin
    assert [round(c, 9) for c in fanuc[-1]] == [5.0, 10.0, 0.0]  # 5 at 0° about (0, 10)


def test_each_g68_replaces_the_rotation():
    a = ends("G68 X0 Y0 R30.\nG68 X0 Y0 R90.\nG01 X10. F100\n")
    assert [round(c, 9) + 0.0 for c in a[-1]] == [0.0, 10.0, 0.0]
    b = ends("G68 X0 Y0 R90000\nG01 X10. F100\n")  # 90000 × 0.001°
    assert [round(c, 9) + 0.0 for c in b[-1]] == [0.0, 10.0, 0.0]
    # G91: "if all command is increment, the actual rotation center is the starting point" (§G68/G69):
    # the centre words are not used, and a note says so; (15, 5) about the start (5, 5) by 90° is (5, 15)
    tp = run("G00 X5. Y5.\nG91 G68 X20. Y20. R90.\nG90 G01 X15. Y5. F100\n")
    assert [round(c, 9) + 0.0 for c in tp.end[-1]] == [5.0, 15.0, 0.0]
    assert tp.notices == ("<program>:2: note: G68 XY in G91: the centre words are not used, the rotation "
                          "centre is the start point (Syntec 8.20 mill programming manual §G68/G69) "
                          "[rotation-centre-ignored]",)
    assert error("G68 X0 Y0\n").code == "missing-value"
    assert ends("G68 X0 Y0 R90.\nG01 X10. F100\nG69\nG91 X1.\n")[-1] == [1.0, 10.0, 0.0]


def test_scaling_factor_without_a_decimal_point_is_thousandths():
    assert ends("G51 X0 Y0 P500\nG01 X10. F100\n") == ends("G51 X0 Y0 P0.5\nG01 X10. F100\n") == [
        [5.0, 0.0, 0.0]]


def test_one_mirrored_axis_reverses_the_rotation():
    """§G51.1: with one axis of the plane mirrored "the direction of coordinate rotation … execute reverse":
    the path is the mirror image of the rotated one, whichever of G51.1 and G68 comes first. (10, 0)
    rotated 30° is (8.660, 5); mirrored about X = 0, (-8.660, 5). Two mirrored axes are a half turn, which
    keeps the direction: (-8.660, -5). G50.1 restores the rotation's own direction."""
    for text in ("G51.1 X0\nG68 X0 Y0 R30.\n", "G68 X0 Y0 R30.\nG51.1 X0\n"):
        end = ends(text + "G01 X10. Y0 F100\n")[-1]
        assert end == pytest.approx([-10 * math.cos(math.radians(30)), 5.0, 0.0], abs=1e-6)
    both = ends("G51.1 X0 Y0\nG68 X0 Y0 R30.\nG01 X10. Y0 F100\n")[-1]
    assert both == pytest.approx([-10 * math.cos(math.radians(30)), -5.0, 0.0], abs=1e-6)
    # about another centre: the image of R_(20,0),90°(30, 0) = (20, 10), mirrored about Y = 0, is (20, -10)
    off = ends("G51.1 Y0\nG68 X20. Y0 R90.\nG01 X30. Y0 F100\n")[-1]
    assert off == pytest.approx([20.0, -10.0, 0.0], abs=1e-6)
    back = ends("G51.1 X0\nG68 X0 Y0 R30.\nG50.1\nG01 X10. Y0 F100\n")[-1]
    assert back == pytest.approx([10 * math.cos(math.radians(30)), 5.0, 0.0], abs=1e-6)


def test_a_mirror_switched_in_compensation_interchanges_g41_and_g42():
    """§G51.1/G50.1: with one mirrored axis the direction of compensation is reversed, so the tool stays
    on the same side of the mirrored contour: square (0,0)-(20,20) traversed CCW with G41 (inside), then
    the same subprogram mirrored about X = 0: the tool is inside the mirrored square too (x in [-15, -5])."""
    text = ("G41 D1 G01 X0 Y0 F100\nM98 H100\nG51.1 X0\nM98 H100\nG50.1\nG40 G00 X0 Y-20.\nM30\n"
            "N100 G01 X20.\nY20.\nX0\nY0\nM99\n")  # fmt: skip
    tp = run(text, tool_offsets={"D": {1: 5.0}})
    mirrored = [p for p in tp.end.tolist() if p[0] < -1e-9]
    assert mirrored and all(-15.0 - 1e-9 <= p[0] <= -5.0 + 1e-9 for p in mirrored[:-1])


# ---------------------------------------------------------------------- calls
def test_label_calls_nest_repeat_and_return():
    text = ("M98 H100 L2\nM98 P20 H5\nM30\nN100 G91 G01 X1. F100\nM98 H200\nM99\nN200 Y1.\nM99\n"
            "O0020\nN1 G90 X90.\nN5 G90 X5.\nM99\n")  # fmt: skip
    assert ends(text) == [[1.0, 0, 0], [1.0, 1.0, 0], [2.0, 1.0, 0], [2.0, 2.0, 0], [5.0, 2.0, 0]]
    assert error("M98 H7\nM30\n").code == "sequence-not-found"
    assert error("M98 L2\n").code == "missing-program-number"
    assert error("M98 P123456\n").code == "bad-call"


def test_m98_h_is_a_label_not_a_length_offset():
    tp = run("G43 H1 G01 Z0 F100\nM98 H100\nG01 Z1.\nM30\nN100 M99\n",
             tool_offsets={"H": {1: 2.0, 100: 50.0}})
    assert tp.end[:, 2].tolist() == [2.0, 3.0]


def test_m99_p_returns_to_a_block_of_the_caller():
    text = "M98 H100\nN10 G01 X9. F100\nN20 X2.\nM30\nN100 G01 Y1. F100\nM99 P20\n"
    assert ends(text) == [[0.0, 1.0, 0.0], [2.0, 1.0, 0.0]]


# ---------------------------------------------------------------------- G37 / G37.1
def test_g37_words_and_alarms():
    settings = {"signal_at": {1: -10.5}}
    tp = run("H1\nG37 Z-10. R2. D1. F200.\nG01 X1.\n", tool_measurement=settings)
    assert tp.end[:, 2].tolist() == [-8.0, -10.5, -10.5]
    assert tp.feed[1] == 200.0 and tp.feed[2] == 1000.0  # F of G37 is the measuring feed only
    assert [bool(m & SegmentMode.OVERRIDE_LOCKED) for m in tp.modes] == [True, True, False]
    # the offset changed by -0.5: G43 H1 now puts Z0 at -0.5
    assert run("H1\nG37 Z-10. R2. D1.\nG43 H1 G01 Z0 F100\n", tool_measurement=settings).end[-1][2] == -0.5
    cases = {"G37 Z-10. R2. D1.\n": 334, "H1\nG37 R2.\n": 330, "H1\nG00 Z-9.\nG37 Z-10. R2. D1.\n": 333,
             "H1\nG37 Z-12. R1. D1.\n": 335, "H1\nG37 Z-9. R1. D1.\n": 336}  # fmt: skip
    for text, alarm in cases.items():
        assert error(text, tool_measurement=settings).alarm == alarm, text


def test_g37_1_returns_to_the_safety_point():
    tp = run("H1\nG37.1 Z-10. R2. Q5.\n", tool_measurement={"signal_at": {1: -9.0}})
    assert tp.end[:, 2].tolist() == [-8.0, -9.0, -8.0, -9.0, 5.0]
    assert tp.feed[3] == 50.0


# ---------------------------------------------------------------------- alarm numbers
def test_errors_carry_syntec_alarm_numbers_only():
    """The family's checks pass GSK alarm numbers (61, 45, 7 …); Syntec numbers only the MAR alarms."""
    assert error(HEAD + "G83 X5. Z-10. R-5.\n").alarm is None  # no Q
    assert error("G01 X1..2\n").alarm is None
