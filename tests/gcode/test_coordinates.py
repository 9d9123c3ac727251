"""Coordinate systems and positioning: G54.1 P1-P48 with G10 L20, G10 L50 parameter input, reference
returns G27/G28/G29/G30, skip G31, single-direction positioning G60, the one-shot exact stop G09, and the
coordinate seam itself (§3.2.7-§3.2.10, §3.2.19-§3.3, §3.8).

The machine starts at the machine origin with every offset zero; reference positions are the machine
origin unless a machine preset says otherwise. Expected points are worked out by hand in each test.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import dataclasses

import pytest
from gcode_helpers import close, moves, program_error, records

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.gcode import get_dialect, interpret, read_program
from cnc_gym.gcode.canonical import rotation_stage
from cnc_gym.gcode.interpreter import Interpreter
from cnc_gym.machine import AxisConfig, MachineConfig
from cnc_gym.toolpath import Plane, SegmentMode


def ends(text: str, **kw) -> list[list[float]]:
    return [r["end"] for r in moves(text, **kw)]


def machine_with_references(**per_axis) -> MachineConfig:
    """A machine whose axes have the given reference_<n>_mm values: per_axis = {"reference_1_mm": (x,y,z)}."""
    axes = tuple(AxisConfig(**{name: values[a] for name, values in per_axis.items()}) for a in range(3))
    return MachineConfig(name="test", axes=axes)  # type: ignore[arg-type]


# --------------------------------------------------------------------------- G54.1 and G10 L20
def test_g54_1_selects_additional_work_systems_set_by_g10_l20():
    # §3.2.20: G10 L20 Pn IP_ sets system n (1..48); G54.1 Pn selects it; no P = P1; G91 adds.
    text = ("G10 L20 P1 X1 Y2\nG10 L20 P48 X-5\nG91 G10 L20 P48 X1 Z3\nG90\n"
            "G54.1 P48 G00 X0 Y0 Z0\nG54.1 X10\nG54 X0 Y0\n")  # fmt: skip
    # G54.1 X10 (P1, offset (1, 2, 0)): X to 1 + 10; Y and Z are not commanded and keep their machine
    # position (§3.2.10).
    assert ends(text) == [[-4.0, 0.0, 3.0], [11.0, 0.0, 3.0], [0.0, 0.0, 3.0]]


def test_g54_1_drops_a_g92_floating_system_like_g54():
    # GSK G92 is replaced by any work system selection (§3.2.13); G54.1 is one.
    assert ends("G00 X10\nG92 X0\nG54.1 P2 X1\n") == [[10.0, 0.0, 0.0], [1.0, 0.0, 0.0]]


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("G54.1 P0\n", "bad-offset-number", 30),  # §3.2.20, alarm 30
        ("G54.1 P49\n", "bad-offset-number", 30),
        ("G54.1 P1.5\n", "bad-offset-number", 30),
        ("G54.1 P1 G04\n", "bad-combination", None),  # "P codes other than offset numbers" (§3.2.20)
        ("G10 L20 P0 X1\n", "bad-g10", 31),
        ("G10 L20 X1\n", "bad-g10", 31),
        ("G10 L20 P1 R1\n", "unused-word", None),
        ("G10 L7 P1 X1\n", "bad-g10", 31),
    ],
)  # fmt: skip
def test_work_system_errors(text, code, alarm):
    err = program_error(text)
    assert err.code == code and err.alarm == alarm


def test_g54_1_is_recorded_for_the_system_variables():
    interp = Interpreter(read_program("G10 L20 P7 X3\nG54.1 P7\n"), get_dialect("gsk25i"))
    interp.run()
    st = interp.state
    assert st.extra_wcs == 7 and st.offsets.active_wcs == 6 + 6  # G54..G59 are 0..5, P1 is 6
    assert interp.program_position == (-3.0, 0.0, 0.0)


# --------------------------------------------------------------------------- G10 L50
def test_worked_example_x16_parameter_input_blocks_are_parsed_and_stored():
    # §3.2.9: `G10L50; N1082 P3 R4500; N1082 P4 R120; G11;` (axis parameter, axes 3 and 4). The
    # first example's R10000000 (bit pattern of P2501) is beyond the reader's R range of ±999999.9999
    # (a known gap, see docs/gcode.md); a bit parameter within it is stored the same way.
    interp = Interpreter(read_program("G10L50\nN1082 P3 R4500\nN1082 P4 R120\nN2501 R999999\nG11\nG00 X1\n"),
                         get_dialect("gsk25i"))  # fmt: skip
    interp.state.parameters.raw.clear()
    toolpath = interp.run()
    assert interp.state.parameters.raw == {(1082, 3): 4500, (1082, 4): 120, (2501, 0): 999999}
    assert interp.state.block_hook is None and len(toolpath) == 1  # G11 closed the mode; X1 ran


@pytest.mark.parametrize(
    ("text", "code"),
    [
        ("G10 L50 X1\nG11\n", "bad-g10"),  # G10 alone in its block (§3.2.9)
        ("G10 L50\nN1880 P1 R1.5\nG11\n", "decimal-point-not-allowed"),  # R has no point (§3.2.9)
        ("G10 L50\nN1880 P1 R#1\nG11\n", "bad-g10"),  # not even from a variable
        ("G10 L50\nG00 X1\nG11\n", "bad-g10"),  # only parameter blocks inside the mode
        ("G10 L50\nN1880 R5\nG11\n", "bad-g10"),  # 1880 is an axis parameter: P1..P5
        ("G10 L50\nN1860 P1 R5\nG11\n", "unused-word"),  # 1860 is not
        ("G10 L50\nN1860 R361000\nG11\n", "bad-parameter"),  # beyond 360.000°
        ("G10 L50\nN1861 R0\nG11\n", "bad-parameter"),
        ("G10 L50\nR5\nG11\n", "bad-g10"),  # no N
    ],
)  # fmt: skip
def test_parameter_input_errors(text, code):
    assert program_error(text).code == code


# --------------------------------------------------------------------------- G28 / G29 / G30 / G27
def test_worked_example_x28_intermediate_point_is_kept_per_axis_and_read_in_the_current_system():
    # §3.3.2 with G55 at (100, 200) so the re-reading in G55 shows; reference position 1 = machine 0.
    #   N1 G90 G54 X0 Y10 → (0, 10)
    #   N2 G28 X40        → X only: (40, 10), then X to the reference: (0, 10)   [intermediate X40]
    #   N3 G29 X30        → X only: to the intermediate (40, 10), then (30, 10)
    #   N4 G01 X20        → (20, 10)
    #   N5 G28 Y60        → Y only: (20, 60), then (20, 0)                         [intermediate X40 Y60]
    #   N6 G55            → no move
    #   N7 G29 X60 Y20    → via (40, 60) *in G55* = machine (140, 260), to G55 (60, 20) = (160, 220)
    text = ("G10 L2 P2 X100 Y200\nN1 G90 G54 X0 Y10\nN2 G28 X40\nN3 G29 X30\nN4 G01 X20 F100\nN5 G28 Y60\n"
            "N6 G55\nN7 G29 X60 Y20\n")  # fmt: skip
    out = moves(text)
    assert [r["end"][:2] for r in out] == [[0, 10], [40, 10], [0, 10], [40, 10], [30, 10], [20, 10], [20, 60],
                                          [20, 0], [140, 260], [160, 220]]  # fmt: skip
    assert all(r["kind"] == "rapid" for i, r in enumerate(out) if i != 5)  # both legs like G00 (§3.3.2)


def test_worked_example_x29_g29_in_g91_is_relative_to_the_intermediate_point():
    # §3.3.3: G90 G0 X10 Y10; G91 G28 X20 Y20 → intermediate (30, 30), then the reference (0, 0).
    # G29 X30 (G91): via (30, 30) to X = 30 + 30 = 60 ("the vector of X axial direction is 60"). Y is not
    # commanded but has an intermediate point: it returns to it and has no further move amount, so the
    # end is the manual's printed (60, 30) (§3.3.3's "other axes remain still" is the minority reading; see
    # transforms.do_g29 and tests/gcode/dialects/gsk25i/test_manual_examples.py).
    out = ends("G90 G0 X10 Y10\nG91 G28 X20 Y20\nG29 X30\n")
    assert out == [[10.0, 10.0, 0.0], [30.0, 30.0, 0.0], [0.0, 0.0, 0.0], [30.0, 30.0, 0.0],
                   [60.0, 30.0, 0.0]]  # fmt: skip
    # Example 1 (§3.3.3): G91 G28 X1000 Y200 (from the origin); M06; G29 X500 Y-400 → via (1000, 200) to
    # (1500, -200).
    out = ends("G91 G28 X1000 Y200\nM06\nG29 X500 Y-400\n")
    assert out[-2:] == [[1000.0, 200.0, 0.0], [1500.0, -200.0, 0.0]]


def test_g28_and_g30_go_to_the_machine_preset_reference_positions():
    machine = machine_with_references(reference_1_mm=(-10.0, 20.0, 100.0), reference_3_mm=(5.0, 6.0, 7.0))
    # G28 Z50: Z to 50, then Z to reference 1's Z (100); X, Y stay.
    assert ends("G00 X1 Y2\nG28 Z50\n", machine=machine)[-2:] == [[1.0, 2.0, 50.0], [1.0, 2.0, 100.0]]
    # G30 P3 X0 Y0: via (0, 0) to reference 3's X, Y.
    assert ends("G30 P3 X0 Y0\n", machine=machine) == [[5.0, 6.0, 0.0]]
    # G30 with no P is P2 (default the origin here); P1051-P1053 written by G10 L50 move points 2-4.
    text = "G10 L50\nN1051 P1 R123000\nG11\nG00 X1\nG30 X1\n"
    assert ends(text)[-1] == [12.3, 0.0, 0.0]


def test_g27_checks_the_reference_position():
    assert ends("G00 X5\nG27 X0 Y0\n") == [[5.0, 0.0, 0.0], [0.0, 0.0, 0.0]]  # on it: no alarm
    err = program_error("G27 X1\n")
    assert err.code == "reference-check-failed" and err.alarm == 46
    machine = machine_with_references(reference_1_mm=(1.0, 0.0, 0.0))
    assert ends("G27 X1\n", machine=machine) == [[1.0, 0.0, 0.0]]


def test_g29_needs_a_stored_intermediate_point_and_g30_p_is_2_to_4():
    assert program_error("G29 X1\n").code == "bad-reference"
    assert program_error("G30 P5 X1\n").code == "bad-reference"


def test_machine_preset_reference_positions_load_from_yaml_keys():
    from cnc_gym.machine import machine_from_dict

    machine = machine_from_dict({"name": "m", "axis_defaults": {"reference_2_mm": -3.5},
                                 "axes": {"z": {"reference_1_mm": 250}}})  # fmt: skip
    assert machine.axis_array("reference_1_mm") == (0.0, 0.0, 250.0)
    assert machine.axis_array("reference_2_mm") == (-3.5, -3.5, -3.5)
    assert dataclasses.asdict(AxisConfig())["reference_4_mm"] == 0.0


# --------------------------------------------------------------------------- G31
def test_worked_example_x15_skip_without_a_signal_completes_the_move():
    # §3.2.8: G31 G91 X100; Y50; — no skip signal in simulation, so X runs to 100 and the
    # incremental Y50 starts there. G31 G90 X200; Y100; likewise ends at (200, 100). G31 moves at the
    # feed like G01; the next block is in the modal G00/G01 of before (G31 is one-shot).
    out = moves("G01 F300\nG31 G91 X100\nY50\n")
    assert [r["end"] for r in out] == [[100.0, 0.0, 0.0], [100.0, 50.0, 0.0]]
    assert out[0]["kind"] == "line" and out[0]["feed"] == 300.0
    assert ends("G01 F300\nG31 G90 X200\nY100\n") == [[200.0, 0.0, 0.0], [200.0, 100.0, 0.0]]


def test_worked_example_x15_with_a_simulated_skip_signal():
    # The probe's surface at X60 (program coordinates). 1) G31 G91 X100; Y50;: the move stops at X60 (the
    # signal) and the incremental Y50 runs from the break point: (60, 50). 2) G31 G90 X200; Y100; with the
    # surface at X150: the absolute Y100 moves Y only, X stays where the signal came: (150, 100)
    # (§3.2.8).
    out = moves("G01 F300\nG31 G91 X100\nY50\n", skip_signal={"X": 60.0})
    assert [r["end"] for r in out] == [[60.0, 0.0, 0.0], [60.0, 50.0, 0.0]]
    # The signal stops the axis; override is disabled on a G31 move (§3.2.8).
    assert out[0]["modes"] == ["exact_stop", "override_locked"] and "modes" not in out[1]
    got = ends("G01 F300\nG31 G90 X200\nY100\n", skip_signal={"X": 150.0})
    assert got == [[150.0, 0.0, 0.0], [150.0, 100.0, 0.0]]
    # A diagonal move stops where it first reaches a surface, all axes at the same fraction; #5061-#5063
    # hold that point. A surface the move does not reach (Y-3 here) changes nothing.
    interp = Interpreter(read_program("G01 F100\nG31 X10 Y20 Z-4\n"), get_dialect("gsk25i"),
                         skip_signal={"Z": -1.0, "Y": -3.0})  # fmt: skip
    interp.run()
    assert interp.state.skip_position == pytest.approx((2.5, 5.0, -1.0))
    # without a signal configured nothing stops (and the move is still override-locked)
    assert moves("G31 X5 F100\n")[0]["modes"] == ["override_locked"]
    for bad in ({"A": 1.0}, {"X": "1"}, {"X": float("nan")}, [1]):
        with pytest.raises(ConfigError):
            interpret("G31 X1 F100\n", skip_signal=bad)


def test_g31_skip_position_is_the_block_end_in_work_coordinates():
    # §3.7.3: with no skip the variables #5061.. get the block end point (work coordinates).
    interp = Interpreter(read_program("G10 L2 P1 X10\nG54 G01 F100\nG31 X5 Y7\n"), get_dialect("gsk25i"))
    interp.run()
    assert interp.state.skip_position == (5.0, 7.0, 0.0)


def test_g31_is_an_alarm_in_cutter_compensation():
    interp = Interpreter(read_program("G31 X5 F100\n"), get_dialect("gsk25i"))
    interp.state.modal[7] = 410  # G41 in force (the compensation module sets the modal table)
    with pytest.raises(ProgramError) as info:
        interp.run()
    assert info.value.code == "g31-in-cutter-compensation" and info.value.alarm == 36


# --------------------------------------------------------------------------- G60
def test_worked_example_x14_single_direction_positioning():
    # §3.2.7: P1880 = (-8, 5, 0) mm; G90 G00 X-10 Y10; G60 X20 Y25: rapid to the end less the overrun,
    # (20 + 8, 25 - 5) = (28, 20), dwell 1 s (§3.2.7), then to (20, 25) in the final approach direction
    # (X negative, Y positive, the signs of the overrun). P1880 in 0.0001 mm through G10 L50.
    text = "G10 L50\nN1880 P1 R-80000\nN1880 P2 R50000\nG11\nG90 G00 X-10 Y10\nG60 X20 Y25\n"
    out = records(text)
    assert [r["kind"] for r in out] == ["rapid", "rapid", "dwell", "rapid"]
    assert out[1]["end"] == [28.0, 20.0, 0.0] and out[3]["end"] == [20.0, 25.0, 0.0]
    assert out[2]["seconds"] == 1.0


def test_g60_without_overrun_or_movement_is_a_plain_rapid():
    # The standard P1880 is 0 (§3.2.7): a plain rapid. An axis that does not move gets no overrun.
    assert [r["kind"] for r in records("G60 X5\n")] == ["rapid"]
    text = "G10 L50\nN1880 P1 R-80000\nN1880 P2 R50000\nG11\nG00 X5 Y5\nG60 Y9\n"
    out = records(text)
    assert [r["end"] for r in out[1:] if r["kind"] != "dwell"] == [[5.0, 4.0, 0.0], [5.0, 9.0, 0.0]]


# --------------------------------------------------------------------------- G09 and path modes
def test_g09_is_a_one_shot_exact_stop():
    out = moves("G01 X10 F100\nG09 X20\nX30\n")
    modes = [SegmentMode(int(m)) for m in interpret("G01 X10 F100\nG09 X20\nX30\n").modes]
    assert [r["end"][0] for r in out] == [10.0, 20.0, 30.0]
    assert modes == [SegmentMode.NONE, SegmentMode.EXACT_STOP, SegmentMode.NONE]


def test_path_modes_g61_to_g64_reach_the_segments():
    tp = interpret("G01 F100\nG61 X1\nG62 X2\nG63 X3\nG64 X4\nG09 G63 X5\n")
    g63 = SegmentMode.OVERRIDE_LOCKED | SegmentMode.TAPPING_MODE
    assert [SegmentMode(int(m)) for m in tp.modes] == [
        SegmentMode.EXACT_STOP, SegmentMode.AUTO_CORNER, g63, SegmentMode.NONE, g63 | SegmentMode.EXACT_STOP,
    ]  # fmt: skip


# --------------------------------------------------------------------------- the seam
def test_seam_move_linear_and_program_position_follow_the_chain():
    interp = Interpreter(read_program(""), get_dialect("gsk25i"))
    interp.state.offsets.wcs[0] = [100.0, 0.0, 0.0]
    interp.state.offsets.update()
    interp.state.chain.set("rotation", rotation_stage(Plane.XY, (0.0, 0.0, 0.0), 90.0))
    interp.set_transform_state()
    interp.state.feed = 500.0
    interp.move_linear(False, (10.0, None, 5.0))
    # program (10, 0, 5) → rotated (0, 10, 5) → + G54 (100, 0, 0)
    assert close(interp.state.out.position, [100.0, 10.0, 5.0])
    assert close(interp.program_position, [10.0, 0.0, 5.0])
    assert close(interp.to_machine((0.0, 10.0, 0.0)), [90.0, 0.0, 0.0])


def test_seam_tool_length_vector_is_added_after_the_transforms_and_kept_by_g92():
    interp = Interpreter(read_program(""), get_dialect("gsk25i"))
    interp.state.chain.set("scaling", None)
    interp.state.offsets.tool_length[2] = 25.0  # what G43 H_ will write (compensation module)
    interp.state.offsets.update()
    interp.move_linear(True, (None, None, 0.0))
    assert interp.state.out.position == (0.0, 0.0, 25.0) and interp.program_position == (0.0, 0.0, 0.0)
    interp.state.offsets.set_floating(2, interp.state.out.position[2], 7.0)  # G92 Z7 with the length active
    interp.state.offsets.update()
    assert interp.program_position == (0.0, 0.0, 7.0)


def test_seam_without_transforms_keeps_the_machine_position_of_omitted_axes():
    # §3.2.10: an omitted axis does not move when the work system changes (the plain path).
    interp = Interpreter(read_program(""), get_dialect("gsk25i"))
    interp.move_linear(True, (1.0, 2.0, 3.0))
    interp.state.offsets.wcs[0] = [10.0, 10.0, 10.0]
    interp.state.offsets.update()
    interp.move_linear(True, (5.0, None, None))
    assert interp.state.out.position == (15.0, 2.0, 3.0)


def test_system_variables_read_the_g54_1_number_and_the_g31_skip_position():
    # #4130 = G54.1 P in force (0 under G54-G59); #5061-#5063 = the G31 end point in work coordinates.
    text = ("G10 L20 P5 X1\nG54.1 P5\n#100=#4130\nG54\n#101=#4130\nG01 F100\nG31 X3 Y4\n"
            "#102=#5061\n#103=#5062\nG00 X#102 Y#103 Z#100\nX#101\n")  # fmt: skip
    assert ends(text)[-2:] == [[3.0, 4.0, 5.0], [0.0, 4.0, 5.0]]


def test_parameter_input_r_has_its_own_eight_digit_range():
    # G10 L50's R is the raw parameter value (§3.2.9): up to 8 digits (a bit parameter's bits 7..0),
    # beyond the R address's ±999999.9999. Outside parameter input the R address's range still holds.
    assert ends("G10 L50\nN2501 R10000000\nG11\nG00 X1\n") == [[1.0, 0.0, 0.0]]
    err = program_error("G10 L50\nN2501 R100000000\nG11\n")
    assert err.code == "value-out-of-range" and err.alarm == 8 and err.line == 2
    for text in ("G01 X1 R10000000 F1\n", "G02 X1 R10000000 F1\n"):
        assert program_error(text).code == "value-out-of-range"
    assert program_error("G10 L50\nN2501 R10000000.5\nG11\n").code == "decimal-point-not-allowed"
