"""The worked examples of the HUST H4C-M manual as golden tests (docs/h4cm_examples.md indexes them: one row
per example, E1-E44).

Each test runs the manual's program (the listing's ``...``/``--`` annotations dropped; a repair is named in
the test and in the index) and compares the tool path with expectations worked out by hand from the
manual's text — points, centres, radii, sweeps and feeds written out with the reasoning, never taken from
the interpreter. The start is (0, 0, 0) unless a test says otherwise. Where the manual contradicts itself
the test follows the reading its own examples support, and says so.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
from h4cm_helpers import close, ends, error, path, run

from cnc_gym.gcode import get_dialect
from cnc_gym.gcode.dialects.h4cm.options import H4cmOptions
from cnc_gym.machine import AxisConfig, MachineConfig


def with_options(**kw):
    return replace(get_dialect("h4cm"), options=H4cmOptions(**kw))


# ---------------------------------------------------------------------- §2.2 programming introduction
def test_e1_a_part_program():
    """§2.2.3: (0,0,0) → (10,10,10) → (20,10,10) → (20,20,10) → (20,20,20) at F200 mm/min, rapid home. The
    manual calls it ten blocks; N70 is not printed."""
    text = ("N10 G00 X0.000 Y0.000 Z0.000\nN20 M3 S1000\nN30 G01 X10.000 Y10.000 Z10.000 F200\nN40 X20.000\n"
            "N50 Y20.000\nN60 Z20.000\nN80 G0 X0.000 Y0.000 Z0.000\nN90 M5\nN100 M2\n")
    assert path(text) == [("F", (10.0, 10.0, 10.0), 200.0), ("F", (20.0, 10.0, 10.0), 200.0),
                          ("F", (20.0, 20.0, 10.0), 200.0), ("F", (20.0, 20.0, 20.0), 200.0),
                          ("R", (0.0, 0.0, 0.0))]  # fmt: skip


P123 = [(12.0, 12.0, 0.0), (26.0, 16.0, 0.0), (38.0, 30.0, 0.0)]


def test_e2_absolute_points():
    """§2.2.4: G90 with X/Y: P1 (12, 12), P2 (26, 16), P3 (38, 30)."""
    assert ends("G00 X0 Y0\nG90\nG1 X12. Y12. F300.00\nX26. Y16.\nX38. Y30.\nM2\n") == P123


def test_e3_incremental_points():
    """§2.2.4: G91 with the increments (12, 12), (14, 4), (12, 14): the same points."""
    assert ends("G00 X0 Y0\nG91\nG1 X12. Y12. F300.00\nX14. Y4.\nX12. Y14.\nM2\n") == P123


def test_e4_uv_incremental_in_g90():
    """§2.2.4: G90 with U/V (incremental X/Y): the same points."""
    assert ends("G00 X0 Y0\nG90\nG1 U12. V12. F300.00\nU14. V4.\nU12. V14.\nM2\n") == P123


def test_e5_mixed_usage_and_uv_ignored_in_g91():
    """§2.2.4 "mixed usage": both printed programs give wrong points (U26. V4. …); our reconstruction mixes
    absolute and incremental words per axis: ``U12. V12. / X26. V4. / U12. Y30.`` and ``U12. V12. /
    U14. Y16. / X38. V14.`` reach P1-P3. Under G91, U/V are "rendered ineffective": no motion."""
    assert ends("G90\nG1 U12. V12. F300.\nX26. V4.\nU12. Y30.\nM2\n") == P123
    assert ends("G90\nG1 U12. V12. F300.\nU14. Y16.\nX38. V14.\nM2\n") == P123
    assert ends("G91\nG1 U12. V12. F300.\nM2\n") == []


def test_e6_m99_in_the_main_program():
    """§2.3.2 "Ex: Program 1": rapid to (0, 0), dwell 1 s, rapid by (480, -480), dwell ``X1`` = 0.001 s (no
    decimal point: least increments), M99. One pass by default; with ``main_m99="restart"`` it starts
    again: with a part-counter limit of 2 the second M99 stops it with ERROR 03 (so it did restart)."""
    text = "N10 G0 X0. Y0.\nN20 G4 X1.\nN30 G0 U480. V-480.\nN40 G4 X1\nN50 M99\n"
    assert path(text) == [("D", 1.0), ("R", (480.0, -480.0, 0.0)), ("D", 0.001)]
    err = error(text, dialect=with_options(counter_limit=2), main_m99="restart")
    assert (err.code, err.alarm, err.line) == ("part-count-limit", 3, 5)


def test_e7_file_order_not_n_order():
    """§2.3.6: inserting N35 or N350 between N30 and N40 changes nothing: blocks run in file order."""
    for label in ("N35", "N350"):
        text = f"N10 G01 X10. F100\nN20 X20.\nN30 X30.\n{label} X35.\nN40 X40.\nN50 M2\n"
        assert [e[0] for e in ends(text)] == [10.0, 20.0, 30.0, 35.0, 40.0]


# ---------------------------------------------------------------------- §3.1-§3.4
def test_e8_g04_is_one_shot():
    """§3.1: G04 is one-shot: the third block is a rapid in the modal G00."""
    assert path("G0 X30. Y40.\nG4 X2.\nX20. Y50.\n") == [("R", (30.0, 40.0, 0.0)), ("D", 2.0),
                                                           ("R", (20.0, 50.0, 0.0))]  # fmt: skip


def test_e9_modal_carry_over():
    """§3.1: G0 stays in force until G1 replaces it; F200 is the feed of the G01."""
    assert path("G0 X10.\nY10.\nG1 X30. F200\n") == [("R", (10.0, 0.0, 0.0)), ("R", (10.0, 10.0, 0.0)),
                                                       ("F", (30.0, 10.0, 0.0), 200.0)]  # fmt: skip


def test_e10_last_g_wins():
    """§3.1: ``G00 G1 X10.000`` runs G01 only (at the power-on feed #112, 1000 mm/min)."""
    assert path("G00 G1 X10.000\n") == [("F", (10.0, 0.0, 0.0), 1000.0)]


def test_e11_rapid_is_one_straight_move():
    """§3.2: ``G00 X100. Y50. Z20.`` is one straight rapid (Fx 10000, Fy 5000, Fz 2000 mm/min: the speeds
    are the controller's, proportional to the distances)."""
    assert path("G00 X100. Y50. Z20.\n") == [("R", (100.0, 50.0, 20.0))]


def test_e12_g01_absolute_and_incremental():
    """§3.3: P1 (25, 20, 10), P2 (60, 50, 40) absolutely and incrementally; the "G90 increment program" is
    printed with X/Y/Z, read as U35. V30. W30."""
    target = [(25.0, 20.0, 10.0), (60.0, 50.0, 40.0)]
    assert ends("G90\nG01 X25. Y20. Z10. F100.00\nX60. Y50. Z40.\n") == target
    assert ends("G91\nG01 X25. Y20. Z10. F100.00\nX35. Y30. Z30.\n") == target
    assert ends("G90\nG01 X25. Y20. Z10. F100.00\nU35. V30. W30.\n") == target


def test_e13_cnc_mode_exact_stop_and_vector_feed():
    """§3.4 CNC mode (#93 = 0): every block ends at a stop; F is the vector feed (Examples 2-3; Example 1's
    per-axis comments are shifted a line and contradict them)."""
    rows = run("G00 X0 Y0 Z0\nG01 X100. F1000.\nG01 X200. Y100. Z50. F500\nG01 X300. F250.\n"
               "G01 X350. F100.\n").to_records()  # fmt: skip
    assert [r["feed"] for r in rows] == [1000.0, 500.0, 250.0, 100.0]
    assert all(r["modes"] == ["exact_stop"] for r in rows)


def _axis_feeds(record) -> tuple[float, float, float]:
    d = [e - s for s, e in zip(record["start"], record["end"], strict=True)]
    length = math.sqrt(sum(c * c for c in d))
    return tuple(record["feed"] * abs(c) / length for c in d)  # type: ignore[return-value]


def test_e14_e15_per_axis_feeds_of_a_vector_f():
    """§3.4 Examples 2-3: ``G1 U100. V50. F1500.`` → Fx = 1500·100/√12500 = 1341.6, Fy = 670.8 (no axis over
    its limit); ``G1 X100. Y200. F2000.`` → 894.4 / 1788.9 unclamped; with a Y limit of 1000 the
    controller scales both to keep the direction: (500, 1000). The clamp is the controller's
    (``max_feed_mm_min`` per axis); the path carries F."""
    (a,) = run("G1 U100.0 V50.0 F1500.00\n").to_records()
    (b,) = run("G1 X100.0 Y200.0 F2000.00\n").to_records()
    assert close(_axis_feeds(a), (1341.641, 670.820, 0.0))
    assert close(_axis_feeds(b), (1200.0 / math.sqrt(1.8), 2400.0 / math.sqrt(1.8), 0.0))
    fy_limit = 1000.0
    scale = fy_limit / _axis_feeds(b)[1]
    assert close((_axis_feeds(b)[0] * scale, fy_limit), (500.0, 1000.0))


def test_e16_master_slave_f_is_the_master_speed():
    """§3.4 master/slave, X master (#93 = 1): F is X's speed: 1000, 500, 250; the block
    ``X200. Y100. Z50. F500.`` moves Δ = (100, 100, 50), |Δ| = 150, so its vector feed is 500·150/100 = 750.
    No stop between blocks."""
    rows = run("G01 X100. F1000.\nX200. Y100. Z50. F500.\nX300. F250.\n",
               dialect=with_options(interpolation_mode=1)).to_records()  # fmt: skip
    assert [r["feed"] for r in rows] == [1000.0, 750.0, 250.0]
    assert [round(_axis_feeds(r)[0], 6) for r in rows] == [1000.0, 500.0, 250.0]
    assert not any(r.get("modes") for r in rows)


def test_e17_master_slave_slaves_in_proportion():
    """§3.4 Example 2 (M/S, X master): ``G01 X100 Y50 Z0 F1000 / X200 Y75 Z50 / X300 Y175 Z100``. The
    numbers have no decimal point: strictly 0.1/0.05 mm, the same ratios (the manual means mm). Fx = 1000
    throughout; Fy = 1000·50/100 = 500, 1000·25/100 = 250, 1000·100/100 = 1000; Fz = 0, 500, 500. (The
    transition N10 → N20 of Y, 0.5·(500-250)/60·100/1000 = 0.208 mm at T = 100 ms, is the preset's
    acc/dec filter.)"""
    rows = run("G01 X100 Y50 Z0 F1000\nX200 Y75 Z50\nX300 Y175 Z100\n",
               dialect=with_options(interpolation_mode=1)).to_records()  # fmt: skip
    assert close(rows[-1]["end"], (0.3, 0.175, 0.1))
    feeds = [_axis_feeds(r) for r in rows]
    assert close([f[0] for f in feeds], [1000.0] * 3)
    assert close([f[1] for f in feeds], [500.0, 250.0, 1000.0])
    assert close([f[2] for f in feeds], [0.0, 500.0, 500.0])
    assert math.isclose(0.5 * (500 - 250) / 60 * 100 / 1000, 0.2083, abs_tol=1e-4)


def test_e18_master_slave_rapids():
    """§3.4 Examples 3-4 (M/S, X master): ``G0 U100. V50.`` and ``G0 U100. V300.`` are straight rapids;
    the speeds (2000, 1000) and the clamp to (1333.33, 4000) are the controller's (docs/h4cm.md)."""
    assert ends("G0 U100. V50.\nG0 U100. V300.\n", dialect=with_options(interpolation_mode=1)) == [
        (100.0, 50.0, 0.0), (200.0, 350.0, 0.0)]  # fmt: skip


# ---------------------------------------------------------------------- §3.5-§3.7 arcs, helix, dwell
def test_e19_four_forms_of_one_arc():
    """§3.5: from (50, 15), ``G02 X30. Y25. J25.`` ≡ ``G02 U-20. V10. J25.`` ≡ ``… R25.`` ≡ ``U-20. V10.
    R25.``: centre (50, 40), r 25, clockwise from -90° to -143.13° (atan2(-15, -20)): -53.13°, 23.18 mm."""
    for words in ("X30. Y25. J25.", "U-20. V10. J25.", "X30. Y25. R25.", "U-20. V10. R25."):
        rows = path(f"G00 X50. Y15.\nG02 {words} F200.\nG01 X0\n")
        assert rows[1] == ("A", (30.0, 25.0, 0.0), (50.0, 40.0, 0.0), 25.0, -53.13), words
    assert math.isclose(25 * math.radians(53.130102), 23.18, abs_tol=0.01)


def test_e20_full_circle_only_with_ijk():
    """§3.5: ``G03 X40. Y0. I50.`` from (40, 0): a full CCW circle about (90, 0), r 50, 314.16 mm, 3.14 min at
    F100; with R the same block is refused (a full circle sweeps 360°)."""
    rows = run("G90\nG00 X40. Y0.\nG03 X40. Y0. I50. F100.\nG01 X0\n").to_records()
    arc = rows[1]
    assert arc["kind"] == "arc" and close(arc["center"], (90.0, 0.0, 0.0)) and arc["sweep_deg"] == 360.0
    assert math.isclose(2 * math.pi * 50 / 100, 3.14, abs_tol=0.01)
    assert error("G00 X40. Y0.\nG03 X40. Y0. R50. F100.\n").code == "arc-r-sweep"


def test_e21_helix():
    """§3.6: ``G17 / G03 X80. Y30. R30. Z40. F100``: the start is in the lost figure; from (110, 0, 0) it is
    a CCW quarter circle about (80, 0) of r 30 to (80, 30) while Z rises to 40."""
    rows = path("G00 X110.\nN1 G17\nN2 G03 X80. Y30. R30. Z40. F100\nG01 X0\n")
    assert rows[1] == ("A", (80.0, 30.0, 40.0), (80.0, 0.0, 0.0), 30.0, 90.0)


def test_e22_dwell():
    """§3.7: ``G4 X2.`` dwells 2 s between the feed and the rapid."""
    assert path("G1 X10. Y10. F100.\nG4 X2.\nG0 X0 Y0\n") == [("F", (10.0, 10.0, 0.0), 100.0), ("D", 2.0),
                                                              ("R", (0.0, 0.0, 0.0))]  # fmt: skip


# ---------------------------------------------------------------------- §3.9 G10
def test_e23_g10_tool_offsets_set_wear_and_add_wear():
    """§3.9.2: ``G10 X0.02 Y0.03 P101`` sets group 1's offsets; ``G10 U0.01 V0.02 W1.72 P102`` sets group 2's
    wear; ``G10 I0.01 J0.02 K1.72 P102`` adds to it. With the Example 3 old wear Z 1.25 (set first), the
    Z wear becomes 1.25 + 1.72 = 2.97 (X 0.02 + 0.01 = 0.03, Y 0.03 + 0.02 = 0.05; the manual's "= 0.05"
    line prints 0.03 + 0.05). The Z column is the G43 length: ``G43 H2`` then Z0 puts the tool at 2.97 + the
    Z offset (0 for group 2)."""
    text = ("G10 X0.02 Y0.03 P101\nG10 U0.02 V0.03 W1.25 P102\nG10 I0.01 J0.02 K1.72 P102\nG43 H2\n"
            "G00 Z0\n")  # fmt: skip
    assert close(ends(text)[-1], (0.0, 0.0, 2.97))
    set_wear = "G10 U0.01 V0.02 W1.72 P102\nG43 H2\nG00 Z0\n"
    assert close(ends(set_wear)[-1], (0.0, 0.0, 1.72))


def test_e24_g65_branches_choose_the_g10_p800_time():
    """§3.9.4 Example 2: #1 < 100 → ``G10 P800 L30``, 100 ≤ #1 < 200 → L50, #1 ≥ 200 → L100 (the text's
    "≤ 100 → 30" disagrees at #1 = 100: the code, L85 "≥", is the oracle). P005 finds N005. G10 P800 (the
    G01 acc/dec time) is a set-up function the simulated machine takes from its preset, so the block is
    refused by name: the line of the refusal shows which branch ran."""
    text = ("N001 G65 L85 P005 A#1 B100\nN002 G10 P800 L30\nN003 M02\nN005 G65 L85 P008 A#1 B200\n"
            "N006 G10 P800 L50\nN007 M02\nN008 G10 P800 L100\nN010 M02\n")
    for value, line in ((99, 4), (100, 7), (199, 7), (200, 9)):
        err = error(f"O001\nG65 L01 P#1 A{value}\n" + text)
        assert (err.code, err.line) == ("not-implemented", line), value
        assert "G10 P800" in err.message


# ---------------------------------------------------------------------- §3.11-§3.15
def _machine(ref1=(100.0, 200.0, 300.0)) -> MachineConfig:
    return MachineConfig(axes=tuple(AxisConfig(reference_1_mm=r) for r in ref1))  # type: ignore[arg-type]


def test_e25_g28_values_only_select_axes():
    """§3.11: ``G40 / G28 X10.``: X only to the 1st reference point; the 10 is ignored."""
    assert ends("G00 X5. Y5.\nG40\nG28 X10.\n", machine=_machine()) == [(5.0, 5.0, 0.0), (100.0, 5.0, 0.0)]


def test_e26_g28_then_g29():
    """§3.12: ``X60. Y0. Z30. / G28 / G29``: all axes to the reference point, then back to (60, 0, 30)."""
    assert ends("G00 X60. Y0. Z30.\nG28\nG29\n", machine=_machine()) == [
        (60.0, 0.0, 30.0), (100.0, 200.0, 300.0), (60.0, 0.0, 30.0)]  # fmt: skip


def test_e27_g31_skip():
    """§3.14: ``G40 / G31 U100.0 F100. / G01 V25.000 / X90.0 Y30.``: the signal (in the lost figure; here at
    X = 60) ends the skip move; the next block starts from the skip point: (60, 25), then (90, 30)."""
    text = "N40 G40\nN50 G31 U100.0 F100.\nN60 G01 V25.000\nN70 X90.0 Y30.\n"
    assert ends(text, skip_signal={"X": 60.0}) == [(60.0, 0.0, 0.0), (60.0, 25.0, 0.0), (90.0, 30.0, 0.0)]
    assert ends(text) == [(100.0, 0.0, 0.0), (100.0, 25.0, 0.0), (90.0, 30.0, 0.0)]


def test_e28_g51_scales_about_the_g51_position():
    """§3.15: after ``G1 X0.0 Y10.0 Z10.0``, ``G51 I2.0 J2.0``, ``X40.0 Y40.0`` cuts ΔX = 2·40 = 80,
    ΔY = 2·(40 - 10) = 60: the end (80, 70)."""
    text = "G1 X0.0 Y10.0 Z10.0 F100\nG51 I2.0 J2.0\nX40.0 Y40.0\nG50\n"
    assert ends(text) == [(0.0, 10.0, 10.0), (80.0, 70.0, 10.0)]


# ---------------------------------------------------------------------- §3.16-§3.18
E29 = ("N1 G0\nN2 G54 X0. Y0.\nN3 G2 I-7.0 F200.0\nN4 G0\nN5 G55 X0. Y0.\nN6 G1 V10.0 F300.\n"
       "N7 G3 V-20.0 R10.0 F300.\nN8 G1 V10.0 F300.\nN9 G28\nN10 M2\n")
# The G54/G55 offsets (-70, -10) and (-80, -30) are MCM data; G10 X Y with the tool at machine (0, 0)
# writes them (offset = machine position - given value).
E29_SETUP = "G54\nG10 X70. Y10.\nG55\nG10 X80. Y30.\n"


def test_e29_work_coordinates_and_the_r_180_block():
    """§3.16.2: G54 = (-70, -10), G55 = (-80, -30). To G54's origin (machine (-70, -10)); a full CW circle
    r 7 about (-77, -10); to G55's origin (-80, -30); up 10; ``G3 V-20.0 R10.0`` is a 180° R arc, which §3.5
    forbids (179°…181°): refused (ERROR 25). With the centre given instead (J-10.), a CCW half circle to
    (-80, -40) through (-90, -30); up 10; G28 to the reference point (machine 0)."""
    err = error(E29_SETUP + E29)
    assert (err.code, err.alarm, err.line) == ("arc-r-sweep", 25, 4 + 7)
    rows = path(E29_SETUP + E29.replace("G3 V-20.0 R10.0", "G3 V-20.0 J-10."), machine=_machine((0, 0, 0)))
    assert rows == [("R", (-70.0, -10.0, 0.0)), ("A", (-70.0, -10.0, 0.0), (-77.0, -10.0, 0.0), 7.0, -360.0),
                    ("R", (-80.0, -30.0, 0.0)), ("F", (-80.0, -20.0, 0.0), 300.0),
                    ("A", (-80.0, -40.0, 0.0), (-80.0, -30.0, 0.0), 10.0, 180.0),
                    ("F", (-80.0, -30.0, 0.0), 300.0), ("R", (0.0, 0.0, 0.0))]  # fmt: skip


def test_e30_mirror_toggles_cut_four_quadrants():
    """§3.17: the pattern in (+X, +Y), then G68 (-X, +Y), G69 (-X, -Y), G68 (+X, -Y), G69 back. The arc is
    clockwise in the original and in the doubly mirrored copy, counter-clockwise where one axis is mirrored
    (implied: a mirror reverses the turning sense)."""
    sub = "O100\nG00 X10. Y10.\nG01 X20. F100\nG02 X30. Y20. R10.\nG01 Y30.\nG00 X0 Y0\nM99\n"
    text = "M98 P100\nG68\nM98 P100\nG69\nM98 P100\nG68\nM98 P100\nG69\nM2\n" + sub
    arcs = [row for row in path(text) if row[0] == "A"]
    quadrants = [(1, 1), (-1, 1), (-1, -1), (1, -1)]
    for (sx, sy), arc in zip(quadrants, arcs, strict=True):
        # from (20, 10) to (30, 20) clockwise about (30, 10): 180° → 90°.
        assert arc[1] == (30.0 * sx, 20.0 * sy, 0.0) and arc[2] == (30.0 * sx, 10.0 * sy, 0.0)
        assert arc[4] == (-90.0 if sx * sy > 0 else 90.0)


def test_e31_absolute_and_incremental():
    """§3.18: ``G90 / X20. Y15. / X35. Y25. / X60. Y30.`` ≡ ``G91 / X20. Y15. / X15. Y10. / X25. Y5.``."""
    points = [(20.0, 15.0, 0.0), (35.0, 25.0, 0.0), (60.0, 30.0, 0.0)]
    assert ends("G90\nG1 X20. Y15. F100\nX35. Y25.\nX60. Y30.\n") == points
    assert ends("G91\nG1 X20. Y15. F100\nX15. Y10.\nX25. Y5.\n") == points


# ---------------------------------------------------------------------- §3.33-§3.37 hole patterns
def _holes(text: str) -> list[tuple[float, float]]:
    """The hole positions: the XY of each feed move to the bottom."""
    feeds = [r for r in run(text).to_records() if r["kind"] == "line"]
    return [(round(r["end"][0], 3), round(r["end"][1], 3)) for r in feeds]


def _pattern(line: str) -> str:
    return f"N001 G81 Z-100. R-50. K0 F100\nN002 {line}\nN003 G80\n"


def test_e32_g34_bolt_circle():
    """§3.34: ``G34 X100. Y100. I50. J45. K4``: 4 holes on r 50 about (100, 100) at 45°, 135°, 225°, 315°:
    100 ± 50·cos 45° = 100 ± 35.355. Each hole: rapid to R -50, feed to -100, rapid back to the start
    level 0."""
    holes = _holes(_pattern("G34 X100. Y100. I50. J45. K4"))
    assert holes == [(135.355, 135.355), (64.645, 135.355), (64.645, 64.645), (135.355, 64.645)]
    rows = path(_pattern("G34 X100. Y100. I50. J45. K4"))
    assert [r[1][2] for r in rows[:4]] == [0.0, -50.0, -100.0, 0.0]


def test_e33_g35_holes_on_a_line():
    """§3.35: ``G35 X100. Y100. I50. J45. K4``: 4 holes 50 apart along 45° from (100, 100), the first at the
    start (the figure is lost): 100 + k·35.355."""
    holes = _holes(_pattern("G35 X100. Y100. I50. J45. K4"))
    assert holes == [(100.0, 100.0), (135.355, 135.355), (170.711, 170.711), (206.066, 206.066)]


def test_e34_g36_holes_on_an_arc():
    """§3.36: ``G36 X100. Y100. I50. J10. P30. K4``: at 10°, 40°, 70°, 100° on r 50 about (100, 100)."""
    expected = [(round(100 + 50 * math.cos(math.radians(a)), 3),
                 round(100 + 50 * math.sin(math.radians(a)), 3)) for a in (10, 40, 70, 100)]  # fmt: skip
    assert expected[0] == (149.240, 108.682)
    assert _holes(_pattern("G36 X100. Y100. I50. J10. P30. K4")) == expected


def test_e35_g37_grid():
    """§3.37 (printed "F37"): ``G37 X100. Y100. I10. P4 J10. K3``: 4 × 3 holes, x 100-130, y 100-120, row
    by row, each row back the way the last came (the visiting order is not printed)."""
    holes = _holes(_pattern("G37 X100. Y100. I10. P4 J10. K3"))
    assert holes == [(100.0, 100.0), (110.0, 100.0), (120.0, 100.0), (130.0, 100.0),
                     (130.0, 110.0), (120.0, 110.0), (110.0, 110.0), (100.0, 110.0),
                     (100.0, 120.0), (110.0, 120.0), (120.0, 120.0), (130.0, 120.0)]  # fmt: skip


def test_e36_m98_once_and_three_times():
    """§3.39.2: ``M98 P05`` calls O5 (printed "05") once, ``M98 P05 L3`` three times."""
    sub = "O5\nG91\nG01 X1. F100\nG90\nM99\n"
    assert [e[0] for e in ends("M98 P05\nM2\n" + sub)] == [1.0]
    assert [e[0] for e in ends("M98 P05 L3\nM2\n" + sub)] == [1.0, 2.0, 3.0]


# ---------------------------------------------------------------------- §3.40 radius compensation
E37 = ("G91\nG01 Z-2.5 F150.\nG17 F300.\nG41 D10 Y30.\nY100.\nX30. Y40.\nG02 X100. I50.\nG01 X30. Y-40.\n"
       "Y-100.\nX-40.\nG03 X-80. R50.\nG01 X-70.\nZ2.5\nG40\nM01\nG0 X130. Y90. F200.\nG01 Z-2.5 F150.\n"
       "G42 Y-40. F300.\nX-60.\nY30.\nG02 X80. I40.\nG01 Y-30.\nX-60.\nZ2.5\nG40 X-60. Y-80.\nM02\n")


def test_e37_radius_compensation_part():
    """§3.40 example (G91, D10 = radius 5 here; the manual's value is on the offset page): programmed
    S(0,0) → A(0,30) → B(0,130) → C(30,170) → D(130,170) CW about (80,170) → E(160,130) → F(160,30) →
    G(120,30) → H(40,30) CCW R50 about (80,0) → I(-30,30); then N(100,120) → O(100,80) → J(40,80) →
    K(40,110) → L(120,110) CW about (80,110) → M(120,80) → P(60,80) → S(0,0).

    G41 keeps the tool 5 left of the path: A…B at x = -5; at the outer corner B an arc of r 5 about B (HUST's
    corner type) to the start of BC's offset; the outer arc CD runs on r 55; F…G at y 25 (left of the
    -Y motion is +X: x = 165; left of -X is -Y: y = 25); G42 (right) on N…O: x = 100 - 5 = 95. The
    cancels return to the programmed points: (-30, 30) and S (0, 0)."""
    rows = run(E37, tool_offsets={"D": {10: 5.0}}).to_records()
    lines = [r for r in rows if r["kind"] == "line"]
    assert close(lines[1]["end"], (-5.0, 30.0, -2.5)) and close(lines[2]["end"], (-5.0, 130.0, -2.5))
    corner = next(r for r in rows if r["kind"] == "arc" and close(r["center"], (0.0, 130.0, -2.5)))
    assert math.isclose(corner["radius"], 5.0) and corner["sweep_deg"] < 0
    cd = next(r for r in rows if r["kind"] == "arc" and close(r["center"], (80.0, 170.0, -2.5)))
    assert math.isclose(cd["radius"], 55.0)
    assert any(close(r["end"], (165.0, 30.0, -2.5)) for r in lines)
    assert any(close(r["end"], (95.0, 85.0, -2.5)) for r in lines)
    assert close(rows[-1]["end"], (0.0, 0.0, 0.0))
    assert any(close(r["end"], (-30.0, 25.0, 0.0)) for r in lines)


# ---------------------------------------------------------------------- §3.41 G65
def test_e41_feed_stock_program():
    """§3.41 Fig 3-38: read I000-I015 (L51 A0), test I005 (AND 32); off → feed #01 (N0010); on and
    #01 < #02 → Error 51 (N0020); on → feed #01 - #02, then a skip move of #02. Variables in µm:
    #01 = 50000 (50 mm), #02 = 20000 (20 mm), feeds #03 = 300, #04 = 100 mm/min."""
    body = ("G65 L51 P#10 A0\nG65 L12 P#11 A#10 B32\nG65 L82 P0010 A#11 B32\nG65 L84 P0020 A#01 B#02\n"
            "G65 L03 P#12 A#01 B#02\nG01 U#12 F#03\nG31 U#02 F#04\nM02\nN0010 G01 U#01 F#03\nM02\n"
            "N0020 G65 L99 P1\nM02\n")

    def setup(one: int, two: int) -> str:
        return f"G65 L01 P#01 A{one}\nG65 L01 P#02 A{two}\nG65 L01 P#03 A300\nG65 L01 P#04 A100\n"

    on = with_options(plc_bits={"I": 1 << 5})
    assert path(setup(50000, 20000) + body, dialect=on) == [("F", (30.0, 0.0, 0.0), 300.0),
                                                            ("F", (50.0, 0.0, 0.0), 100.0)]  # fmt: skip
    assert path(setup(50000, 20000) + body) == [("F", (50.0, 0.0, 0.0), 300.0)]  # I005 off
    err = error(setup(10000, 20000) + body, dialect=on)
    assert (err.code, err.alarm, err.line) == ("user-alarm", 51, 4 + 11)


@pytest.mark.parametrize("name", ["E42", "E43", "E44"])
def test_e42_e44_are_parameter_arithmetic(name):
    """§4.2: resolution (pitch 5 mm, 2500 ppr, ×4, 5:1 → 1/10 µm a pulse), limit-switch length (3000 mm/min
    × 100 ms / 60000 = 5 mm) and pitch-error distribution (0.026 mm over 8 points → 3,3,3,4,3,3,3,4 µm)
    compute machine parameters, not a tool path; the arithmetic is checked here as printed."""
    if name == "E42":
        assert math.isclose(5000 / (2500 * 4) / 5, 0.1)
    elif name == "E43":
        assert 3000 * 100 / 60000 == 5.0
    else:
        steps, carried, total = [], 0.0, 0
        for k in range(1, 9):
            target = math.floor(26 * k / 8 + 1e-9)
            steps.append(target - total)
            total = target
        assert steps == [3, 3, 3, 4, 3, 3, 3, 4] and carried == 0.0
