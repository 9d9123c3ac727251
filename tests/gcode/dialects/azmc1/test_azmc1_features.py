"""The AZ-MC1's features one by one (AMK AZ-MC1 programming manual §3, §4, §11, §12), with expectations
worked out by hand, and the dialect on the command line, in bench and in the env."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest

import cnc_gym  # noqa: F401  (registers the env)
from cnc_gym import cli
from cnc_gym.errors import ProgramError
from cnc_gym.gcode import get_dialect, interpret
from cnc_gym.gcode.dialects.azmc1.options import AzOptions
from cnc_gym.machine import load_machine, machine_from_dict
from cnc_gym.toolpath import SegmentKind, SegmentMode

AZ = get_dialect("azmc1")


def run(text: str, **kw):
    return interpret(text, dialect=kw.pop("dialect", AZ), file="f.din", **kw)


def ends(text: str, **kw) -> list[tuple]:
    return [tuple(round(c, 4) + 0.0 for c in row) for row in run(text, **kw).end.tolist()]


def error(text: str, **kw) -> ProgramError:
    with pytest.raises(ProgramError) as info:
        run(text, **kw)
    return info.value


# ---------------------------------------------------------------------- motion and modes
def test_power_on_is_g01_and_a_feed_is_needed():
    assert run("G1 F100\nX5\nM30\n").kind.tolist() == [SegmentKind.LINE]
    assert run("F100\nX5\nM30\n").kind.tolist() == [SegmentKind.LINE]  # G01 is the basic state
    assert error("X5\n").code == "missing-feed"


def test_g161_absolute_and_g162_relative_centres():
    # From (10, 0), a CCW quarter to (0, 10) about the origin: G162 I-10 J0, G161 I0 J0.
    relative = run("G0 X10\nG3 X0 Y10 I-10 J0 F100\nM30\n")
    absolute = run("G0 X10\nG161 G3 X0 Y10 I0 J0 F100\nM30\n")
    for toolpath in (relative, absolute):
        assert toolpath.center[1].tolist()[:2] == [0, 0] and math.isclose(toolpath.sweep[1], math.pi / 2)
    # I/J are not modal; an omitted one is 0 in G162 and an error in G161.
    assert run("G0 X10\nG3 X-10 Y0 I-10 F100\nM30\n").center[1].tolist()[:2] == [0, 0]
    assert error("G0 X10\nG161 G3 X-10 Y0 I0 F100\n").code == "arc-missing-center"
    assert error("G0 X10\nG3 X-10 Y0 F100\n").code == "arc-missing-center"
    assert error("G0 X10\nG3 X-10 Y0 I-10 K1 F100\n").code == "arc-bad-offset"


def test_g18_arcs_use_i_and_k():
    toolpath = run("G18\nG0 X10\nG2 X0 Z10 I-10 K0 F100\nM30\n")
    assert toolpath.center[1].tolist() == [0, 0, 0] and toolpath.plane[1] == 1  # ZX


def test_g60_and_g63_are_one_block_g36_is_modal():
    toolpath = run("G1 F100 X1 G60\nX2\nX3 G63\nX4\nG36\nX5\nY5\nG37\nX6\nM30\n")
    modes = [SegmentMode(int(m)) for m in toolpath.modes]
    assert modes[0] == SegmentMode.EXACT_STOP and modes[1] == SegmentMode.NONE
    assert modes[2] == SegmentMode.OVERRIDE_LOCKED and modes[3] == SegmentMode.NONE
    assert modes[4] == modes[5] == SegmentMode.ROUND_BLOCK_END and modes[6] == SegmentMode.NONE


def test_g09_is_accepted_and_g08_is_refused_by_name():
    assert ends("G1 F100 X1 G09\nM30\n") == [(1, 0, 0)]
    err = error("G08 G1 F100 X1\n")
    assert err.code == "not-implemented" and "overview" in err.message


def test_g70_converts_distances_but_not_feed_or_offsets():
    # §3.6: X1 in G70 is 25.4 mm; F100 stays 100 mm/min; D1's length (10 mm) and G92 X1 stay mm.
    toolpath = run("G70 G1 X1 F100\nG92 X1\nG0 X0\nD1 Z0\nG71\nX2\nM30\n", tool_offsets={"H": {1: 10.0}})
    assert toolpath.end.tolist() == [[25.4, 0, 0], [1, 0, 0], [1, 0, 10], [3, 0, 10]]
    assert toolpath.feed[0] == 100


def test_power_on_units_select_g70():
    # units="inch" puts G70 in force at power-on; F stays in mm/min.
    toolpath = run("G1 X1 F100\nM30\n", units="inch")
    assert toolpath.end.tolist() == [[25.4, 0, 0]] and toolpath.feed[0] == 100


def test_g95_feed_per_revolution():
    toolpath = run("S500 M3\nG95 G1 X10 F0.2\nM30\n")
    assert toolpath.feed[0] == pytest.approx(100)  # 0.2 mm/rev × 500 rev/min


# ---------------------------------------------------------------------- coordinates
def test_zero_offsets_g53_to_g59():
    az = replace(AZ, options=AzOptions(zero_offsets={2: (100, 50, 0), 7: (-10, -20, -30)}))
    text = "G0 X1 Y1\nG54 X1 Y1\nG59 X1 Y1 Z1\nG55 X1\nG53 X1 Y1 Z1\nM30\n"
    # G54 (entry 02) offsets; only programmed axes move; G55 (entry 03) is zero; G53 none.
    assert ends(text, dialect=az) == [(1, 1, 0), (101, 51, 0), (-9, -19, -29), (1, -19, -29), (1, 1, 1)]


def test_g92_stacks_on_the_zero_offset_and_survives_a_zpo_change():
    az = replace(AZ, options=AzOptions(zero_offsets={2: (100, 0, 0)}))
    assert ends("G54 G92 X10\nG0 X0\nG53\nX0\nG92 X0\nX0\nM30\n", dialect=az) == [(110, 0, 0), (10, 0, 0),
                                                                               (0, 0, 0)]  # fmt: skip
    assert error("G92\n").code == "missing-value"


def test_mirroring_about_the_program_zero():
    # G21 mirrors X, G22 Y, G23 both; a one-axis mirror reverses the arc; G20 cancels.
    toolpath = run("G1 F100\nG21 X10 Y5\nG22 X10 Y5\nG23 X10 Y5\nG20 X10 Y5\nG21 G2 X-10 Y-5 I-10 J-5\nM30\n")
    assert toolpath.end.tolist()[:4] == [[-10, 5, 0], [10, -5, 0], [-10, -5, 0], [10, 5, 0]]
    assert toolpath.sweep[4] > 0  # G02 mirrored in one axis runs counter-clockwise
    err = error("D1 G41 G1 X1 F100\nG21\n", tool_offsets={"D": {1: 1.0}})
    assert err.code == "mirror-in-tro" and err.line == 2


def test_soft_limits_set_add_and_check_arc_extremes():
    # G91 G99 adds to the limit; an arc that bulges past a limit is caught at its extreme.
    text = "G99 X50 Y50\nG91 G99 X10\nG90 G0 X60\nM30\n"
    assert ends(text) == [(60, 0, 0)]
    assert error(text.replace("X60", "X60.001")).code == "soft-limit"
    assert len(run("G99 Y10\nG0 X-5\nG2 X5 Y0 I5 J0 F100\nM30\n")) == 2  # the top of the circle: Y5 ok
    err = error("G99 Y4\nG0 X-5\nG2 X5 Y0 I5 J0 F100\nM30\n")  # Y5 > 4
    assert err.code == "soft-limit" and err.line == 3 and "Y5.0000" in err.message
    assert error("G98 X10\nG99 X5\n").code == "soft-limit"  # − above +


def test_soft_limits_set_in_a_loop_are_checked_per_pass():
    # A limit set in every pass of a loop: each segment meets the limit in force when it was made; pass 700
    # overshoots its own limit by 0.5 mm (one epoch of 1000, found without a loop over them).
    text = ("R1 = 0\n$WHILE R1 < 1000\nR1 = R1 + 1\nG99 Y R1 + 0.5\nG1 F1000 Y R1 + [R1 == 700]\n"
            "$ENDWHILE\nM30\n")
    assert len(run(text.replace(" + [R1 == 700]", ""))) == 1000
    err = error(text)
    assert err.code == "soft-limit" and err.line == 5
    assert "Y701.0000" in err.message and "Y700.5" in err.message


def test_soft_limits_start_at_the_machine_travel():
    # §3.1.7: the limits are preset from the axis data at run-up; G91 G99 X-10 pulls the + limit of a
    # machine with X up to 500 mm 10 mm in.
    machine = machine_from_dict({"axis_defaults": {"min_position_mm": -500, "max_position_mm": 500}},
                                source="travel.yaml")  # fmt: skip
    text = "G91 G99 X-10\nG90 G0 X490\nM30\n"
    assert ends(text, machine=machine) == [(490, 0, 0)]
    err = error(text.replace("X490", "X491"), machine=machine)
    assert err.code == "soft-limit" and err.line == 2


def test_soft_limits_check_the_compensated_path():
    # The tool centre, not the programmed contour, meets the limit switch: D1 r = 2 on the left of +X.
    text = "G99 Y1\nD1\nG41 G1 X10 Y0 F100\nX20\nG40 X30\nM30\n"
    err = error(text, tool_offsets={"D": {1: 2.0}})
    assert err.code == "soft-limit" and "Y2.0000" in err.message


def test_g74_homes_to_the_machine_reference_and_99_is_a_resync():
    machine = load_machine("vmc-small")
    reference = machine.axis_array("reference_1_mm")
    toolpath = run("G0 X10 Y20 Z-30\nG74 Z1 X99\nM30\n", machine=machine)
    assert toolpath.end[-1].tolist() == [10, 20, reference[2]]
    assert len(run("G74 X99\nM30\n")) == 0
    assert error("G74 X98\n").code == "not-implemented"
    assert error("G74 X0\n").code == "bad-homing"
    assert error("G74\n").code == "bad-homing"


# ---------------------------------------------------------------------- tool offsets
OFFSETS = {"H": {1: 10.0, 2: 25.0}, "D": {1: 2.0, 2: 3.0}}


def test_tool_length_follows_the_plane_and_rides_on_the_first_move():
    # G17: Z carries the length, only when Z moves; G18: Y; G19: X. D00 cancels with the next move.
    assert ends("D1 G0 X5\nZ0\nD0\nZ0\nM30\n", tool_offsets=OFFSETS) == [(5, 0, 0), (5, 0, 10), (5, 0, 0)]
    assert ends("G18 D2 G0 X5 Y0\nM30\n", tool_offsets=OFFSETS) == [(5, 25, 0)]
    assert ends("G19 D2 G0 X5 Y1\nM30\n", tool_offsets=OFFSETS) == [(30, 1, 0)]
    assert ends("D1\nG91 G0 Z-5\nM30\n", tool_offsets=OFFSETS) == [(0, 0, 5)]  # incremental too


def test_new_d_in_tro_needs_no_new_g41():
    # G41 with D1 (r 2) along +X, then D2 (r 3) in a later block: the offset changes without G41 again.
    toolpath = run("G0 X0 Y-10 D1\nG41 G1 X0 Y0 F100\nX10\nD2 X20\nX30\nG40 X30 Y-10\nM30\n",
                   tool_offsets={"D": {1: 2.0, 2: 3.0}})  # fmt: skip
    ys = [round(y, 4) for y in toolpath.end[:, 1].tolist()]
    assert 2.0 in ys and 3.0 in ys


def test_tro_rules():
    offsets = {"D": {1: 2.0}}
    err = error("G0 D1\nG41 G1 X10 F100\nG42 X20\n", tool_offsets=offsets)
    assert (err.code, err.line) == ("tro-direct-change", 3)
    err = error("G0 D1\nG41 G1 X10 F100\nX20\nG40\n", tool_offsets=offsets)
    assert (err.code, err.line) == ("tro-deselect-no-travel", 4)
    err = error("G41 G1 X10 F100\n")
    assert (err.code, err.line) == ("tro-no-d", 1)
    err = error("G0 D1\nG41\nG2 X10 Y0 I5 F100\n", tool_offsets=offsets)
    assert (err.code, err.line) == ("comp-arc-startup", 3)


@pytest.mark.parametrize("radius", [0.0, 2.0])
def test_tro_selection_or_withdrawal_on_a_circle_is_refused_whatever_the_radius(radius):
    """§11.3.1: "Selection of the TRO with a contour combination Circle - Straight line, Circle - Circle
    leads to an error message" — the D record's radius does not enter the rule, so a D with radius 0 is
    refused too (the Fanuc family's stage, which only starts up with a radius, would let it pass); the same
    for the withdrawal after G40 (§11.3.4). A straight travel in the plane first, then circles are fine."""
    offsets = {"D": {1: radius}}
    for text, line in (("G0 D1\nG41\nG2 X10 Y0 I5 F100\n", 3), ("G0 D1\nG41 G2 X10 Y0 I5 F100\n", 2),
                       ("G0 D1\nG41 G1 Z-1 F100\nG3 X10 Y0 I5\n", 3),
                       ("G0 D1\nG41 G1 X10 F100\nG40 G2 X20 Y0 I5\n", 3)):
        err = error(text, tool_offsets=offsets)
        assert (err.code, err.line) == ("comp-arc-startup", line), (text, str(err))
    run("G0 D1\nG41 G1 X10 F100\nG2 X20 Y0 I5\nG40 G1 X30 Y-10\nG2 X40 Y-10 I5\nM30\n", tool_offsets=offsets)


def test_g138_direct_and_g139_transition_approach():
    # Start-up from (0, -10) along +Y to (0, 0), then +X: a right turn, outside for G41 (r 2). G138 (direct,
    # §11.3.1): the approach block runs to the point perpendicular to the next block's start, (0, 0) +
    # 2·(0, 1) = (0, 2). G139 (with transition blocks): the start-up block keeps its own offset x = -2 to
    # the corner's intersection with the next block's offset line y = 2: (-2, 2).
    text = "G0 X0 Y-10 D1\n{code} G41 G1 X0 Y0 F100\nX10\nG40 X20 Y-10\nM30\n"
    direct = run(text.format(code="G138"), tool_offsets={"D": {1: 2.0}}).end.tolist()
    transition = run(text.format(code="G139"), tool_offsets={"D": {1: 2.0}}).end.tolist()
    assert direct[1] == [0, 2, 0] and transition[1] == [-2, 2, 0]
    assert run(text.format(code=""), tool_offsets={"D": {1: 2.0}}).end.tolist()[1] == [-2, 2, 0]  # G139


def test_a_contour_violation_is_an_error_not_corrected():
    # The family's dip example (a CCW half circle R5 dipping under a line, offset 6): the Fanuc family
    # bridges it with a straight line; the AZ-MC1 recognises a contour violation (§11.3.5).
    text = "G0 X-20 D1\nG41 G1 X-10 Y0 F100\nX10\nG3 X20 Y0 I5 J0\nG1 X30\nG40 X40\nM30\n"
    err = error(text, tool_offsets={"D": {1: 6.0}})
    assert err.code == "comp-interference" and err.line == 4 and "contour violation" in err.message
    fanuc = interpret("G00 X-20\nG01 G41 D1 X-10 Y0 F100\nX10\nG03 X20 Y0 I5 J0\nG01 X30\nG40 X40\n",
                      tool_offsets={"D": {1: 6.0}})  # fmt: skip
    assert len(fanuc) == 6


# ---------------------------------------------------------------------- M functions and words
def test_m_functions_refused_by_name_and_machine_specific():
    for code in ("M17", "M18", "M20", "M21", "M22", "M27", "M28", "M96"):
        err = error(f"{code} S50\n")
        assert err.code == "not-implemented" and code in err.message
    err = error("M80\n")
    assert err.code == "unknown-code" and "machine-specific" in err.message
    assert error("M8\n").code == "unknown-code"
    assert error("G74 X1 M5\n").code == "bad-combination"


def test_spindle_2_h_words_and_m26():
    toolpath = run("M13 S100\nH7 M26\nG1 X1 F100\nM15\nM30\n")
    assert toolpath.end.tolist() == [[1, 0, 0]] and toolpath.spindle_rpm[0] == 0  # spindle 1 is off
    with pytest.raises(ProgramError):
        run("M13 M14\n")  # two spindle-2 functions in one block


def test_m25_s_is_not_a_spindle_speed():
    az = replace(AZ, options=AzOptions(plc_transfer={3: 2.5}))
    toolpath = run("S800 M3\nM25 S3\nG1 X R1003 F100\nM30\n", dialect=az)
    assert toolpath.end[0, 0] == 2.5 and toolpath.spindle_rpm[0] == 800


def test_tool_table_errors():
    assert error("R1 = TLOC[41]\n").code == "bad-tool"
    assert error("R1 = TLOC[1.5]\n").code == "bad-tool"


def test_options_are_checked():
    from cnc_gym.errors import ConfigError

    with pytest.raises(ConfigError, match="entry 8"):
        AzOptions(zero_offsets={8: (0, 0, 0)})
    with pytest.raises(ConfigError, match="D number 41"):
        AzOptions(tools={41: None})  # type: ignore[dict-item]


# ---------------------------------------------------------------------- CLI, bench, env
PROGRAM = ("%300\nG0 X0 Y0 Z5\nG1 Z-1 F600\nR1 = 0\n$WHILE R1 < 2\nG1 X20 F1200\nY20\nX0\nY0\nR1 = R1 + 1\n"
           "$ENDWHILE\nM30\n")


def test_cli_trace_and_run_take_the_dialect(tmp_path, capsys):
    path = tmp_path / "square.din"
    path.write_text(PROGRAM)
    assert cli.main(["trace", str(path), "--dialect", "azmc1"]) == 0
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert len(lines) == 2 + 8 and lines[-1]["end"] == [0.0, 0.0, -1.0]
    assert cli.main(["run", str(path), "--dialect", "azmc1", "--json", "--max-time", "60"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["finished"] and result["cycle_time_s"] > 0
    bad = tmp_path / "bad.din"
    bad.write_text("G1 F100\nX50R1=7\n")
    assert cli.main(["trace", str(bad), "--dialect", "azmc1"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.strip().startswith(f"{bad}:2: ") and "[syntax]" in captured.err


def test_bench_takes_the_dialect(tmp_path, capsys):
    path = tmp_path / "square.din"
    path.write_text(PROGRAM)
    out = tmp_path / "b.jsonl"
    code = cli.main(["bench", "--programs", str(path), "--dialect", "azmc1", "--policy", "constant:1.0",
                     "--no-progress", "--json", str(out)])  # fmt: skip
    assert code == 0
    record = json.loads(out.read_text().splitlines()[0])
    assert record["program"] and record["cycle_time_s"] > 0


def test_env_takes_the_dialect(tmp_path):
    path = tmp_path / "square.din"
    path.write_text(PROGRAM)
    env = gym.make("cnc_gym/Feedrate-v0", dialect="azmc1", programs=[str(path)])
    obs, _info = env.reset(seed=0)
    assert np.all(np.isfinite(obs))
    obs, reward, *_ = env.step(env.action_space.sample())
    assert np.isfinite(reward)
    env.close()
