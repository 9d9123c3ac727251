"""The H4C-M's input rules, words and motion codes (HUST H4C-M manual §2.2-§2.3, §3.1-§3.14): each test
states the rule with its section and the expected path worked out by hand."""

from __future__ import annotations

import pytest
from h4cm_helpers import close, ends, error, path, run

from cnc_gym.gcode import get_dialect
from cnc_gym.machine import AxisConfig, MachineConfig


# ---------------------------------------------------------------------- input (§2.3)
def test_numbers_without_a_point_count_least_increments_and_integer_f_is_mm_per_min():
    # §2.3.5: X2 = 0.002 mm, Y250 = 0.250 mm, W125. = 125 mm; F200 is 200 mm/min, not 0.2.
    assert path("G01 X2 Y250 F200\nG01 Z125.\n") == [("F", (0.002, 0.25, 0.0), 200.0),
                                                     ("F", (0.002, 0.25, 125.0), 200.0)]  # fmt: skip
    # In G20 the least increment is 0.0001 inch: X2 is 0.0002 inch = 0.00508 mm; a variable likewise.
    assert ends("G20\nG01 X2 F10\nG65 L01 P#1 A2500\nG01 X#1\n") == [(0.005, 0.0, 0.0), (6.35, 0.0, 0.0)]
    # G04 X without a point counts milliseconds in either unit.
    assert path("G20\nG04 X1\nG04 X1.5\n") == [("D", 0.001), ("D", 1.5)]


def test_a_block_holds_at_most_64_characters():
    ok = "N1 G01 X1.000 Y2.000 Z3.000 F100" + " " * 32  # 64 characters
    assert len(ok) == 64
    run(ok + "\n")
    err = error("G00 X0\n" + ok + "M5\n")
    assert (err.code, err.alarm, err.line) == ("block-too-long", 8, 2)


def test_power_on_state_is_g01_at_the_feed_of_mcm_112():
    # Table 3-1: G01 is the power-on motion; #112 (1000 mm/min) is its feed before any F.
    assert path("X10.\n") == [("F", (10.0, 0.0, 0.0), 1000.0)]


def test_n_labels_are_strings():
    # §2.3.6: "N10, N010, N0010 are three different block numbers"; a jump to P010 finds N010 only.
    text = ("G65 L80 P010\nN10 G01 X1. F100\nN010 G01 Y1.\nM02\n")
    assert ends(text) == [(0.0, 1.0, 0.0)]
    text = ("G65 L80 P0010\nN10 G01 X1. F100\nN010 G01 Y1.\nM02\n")
    assert error(text).code == "sequence-not-found"


def test_execution_is_in_file_order_whatever_the_n_values():
    # §2.3.6 (E7): N35 or N350 between N30 and N40 changes nothing.
    for n in ("N35", "N350"):
        text = f"N10 G01 X1. F100\nN30 X2.\n{n} X3.\nN40 X4.\nM02\n"
        assert [e[0] for e in ends(text)] == [1.0, 2.0, 3.0, 4.0]


def test_brackets_and_assignments_are_refused_by_name():
    assert error("G01 X[1+2] F100\n").code == "bad-expression"
    assert error("#1=5\n").code == "bad-expression"


# ---------------------------------------------------------------------- one G per block (§3.1)
def test_the_last_g_code_of_a_block_wins():
    # §3.1: "G00 G1 X10.000" runs G01 only.
    assert path("G00 G1 X10. F300\n") == [("F", (10.0, 0.0, 0.0), 300.0)]
    # "G91 G00" runs G00 only: the G91 is lost, the second X5. is absolute again and does not move.
    assert path("G91 G00 X5.\nX5.\n") == [("R", (5.0, 0.0, 0.0))]


# ---------------------------------------------------------------------- U/V/W (§2.2.4, §3.18)
def test_uvw_are_incremental_in_g90_and_ignored_in_g91():
    assert ends("G00 X10. Y10.\nG01 U5. V-2. W1. F100\n") == [(10.0, 10.0, 0.0), (15.0, 8.0, 1.0)]
    # G91: U/V/W "rendered ineffective": no motion on those axes.
    assert ends("G91\nG01 U5. Y2. F100\n") == [(0.0, 2.0, 0.0)]
    # A block's own G91/G90 decides: "G91 U5." moves nothing, "G90 U5." (from G91) moves by 5.
    assert ends("G00 X1.\nG91 U5. Y2.\n") == [(1.0, 0.0, 0.0), (1.0, 2.0, 0.0)]
    assert ends("G91\nG00 X1.\nG90 U5. Y2.\n") == [(1.0, 0.0, 0.0), (6.0, 2.0, 0.0)]


def test_with_x_and_u_in_one_block_u_wins():
    # §2.3.6: "G1 X100. U50." moves by U50.
    assert ends("G00 X10.\nG1 X100. U50. F100\n") == [(10.0, 0.0, 0.0), (60.0, 0.0, 0.0)]


# ---------------------------------------------------------------------- G04 (§3.7)
def test_g04_dwells_x_seconds_and_x_without_a_point_counts_milliseconds():
    assert path("G04 X2.\nG04 X1\n") == [("D", 2.0), ("D", 0.001)]
    assert error("G04 P100\n").code == "unused-word"
    assert error("G04 X9000.\n").code == "bad-dwell"


# ---------------------------------------------------------------------- arcs (§3.5)
def test_r_arcs_near_0_and_180_degrees_are_refused():
    # §3.5: "do not use R" for sweeps of -10°…+10° and 179°…181°. A half circle of R10 sweeps 180°.
    err = error("G00 X0 Y0\nG03 X-20. Y0 R10. F100\n")
    assert (err.code, err.alarm, err.line) == ("arc-r-sweep", 25, 2)
    # A 5° chord with R: 2·R·sin(2.5°) = 0.8724 mm for R10.
    assert error("G02 X0.872 Y0 R10. F100\n").code == "arc-r-sweep"
    # 90° is fine: from (0, 0) to (10, 10) R10 CW, centre (10, 0) (from 180° to 90°, clockwise).
    assert path("G02 X10. Y10. R10. F100\nG01 X11.\n")[0] == ("A", (10.0, 10.0, 0.0), (10.0, 0.0, 0.0), 10.0,
                                                                -90.0)  # fmt: skip


def test_an_arc_must_be_followed_by_a_g00_or_g01_block():
    # §3.5: otherwise Error 25. Blocks without motion (M, F, G04) may come between.
    run("G02 X10. Y10. R10. F100\nM05\nG04 X1.\nG01 X20.\n")
    for after in ("X0 Y20.", "G03 X0 Y20. R10."):
        err = error(f"G02 X10. Y10. R10. F100\n{after}\n")
        assert (err.code, err.alarm, err.line) == ("arc-mode", 25, 2)


def test_full_circle_only_with_ijk():
    # §3.5 (E20): G03 X40 Y0 I50 from (40, 0) is a full CCW circle about (90, 0), 314.16 mm long.
    rows = path("G00 X40. Y0\nG03 X40. Y0 I50. F100.\nG01 X0\n")
    assert rows[1] == ("A", (40.0, 0.0, 0.0), (90.0, 0.0, 0.0), 50.0, 360.0)
    assert error("G00 X40. Y0\nG03 X40. Y0 R50. F100.\n").code == "arc-r-sweep"


# ---------------------------------------------------------------------- G28/G29/G30/G08 (§3.8, §3.11-§3.13)
def _machine() -> MachineConfig:
    axes = (AxisConfig(reference_1_mm=100.0, reference_2_mm=-50.0), AxisConfig(reference_1_mm=200.0),
            AxisConfig(reference_1_mm=300.0, reference_2_mm=10.0))  # fmt: skip
    return MachineConfig(axes=axes)


def test_g28_values_only_select_axes_and_g29_returns():
    m = _machine()
    # E25: G28 X10. moves X only to the reference point, the 10 is ignored; no intermediate point.
    assert ends("G00 X60. Y5. Z30.\nG28 X10.\n", machine=m) == [(60.0, 5.0, 30.0), (100.0, 5.0, 30.0)]
    # E26: G28 alone: all axes; G29 back to (60, 0, 30).
    rows = ends("G00 X60. Y0 Z30.\nG28\nG29\n", machine=m)
    assert rows == [(60.0, 0.0, 30.0), (100.0, 200.0, 300.0), (60.0, 0.0, 30.0)]
    # G30: the 2nd reference point of the named axes.
    assert ends("G00 X1.\nG30 X0 Z0\n", machine=m)[-1] == (-50.0, 0.0, 10.0)
    assert error("G29\n").code == "bad-reference"


def test_g08_is_refused_by_name():
    err = error("G08 X0\n")
    assert err.code == "not-implemented" and "G08" in err.message and err.alarm == 13


def test_codes_the_h4cm_does_not_have_are_error_13():
    for code in ("G73", "G92", "G61", "G16", "G52"):
        err = error(f"{code} X1.\n")
        assert (err.code, err.alarm) == ("unknown-code", 13), code
    err = error("G84 X0 Y0 Z-5. R1. F100\n")
    assert (err.code, err.alarm) == ("not-implemented", 13)


def test_the_dialect_record():
    d = get_dialect("h4cm")
    assert d.roles.macro_call is None  # G65 is not a macro call
    assert d.max_subprogram_nesting == 5
    assert close(run("G01 X1. F100\n").end[-1], (1.0, 0.0, 0.0))


@pytest.mark.parametrize("text", ["G17 F300.\nG01 X1.\n", "N3 G17 F300.\n"])
def test_plane_blocks_may_carry_f(text):
    run(text)
