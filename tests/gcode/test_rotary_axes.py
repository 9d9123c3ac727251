"""Rotary axes A/B/C in the interpreter (manual §3.2.2, example X8): words, positions and the feed
rule.

The GSK 25i counts a rotary axis's degrees like millimetres in the feed: in a block that moves linear and
rotary axes together F is the rate along the composite vector, and a rotary-only G01 runs at F deg/min.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import interpret
from cnc_gym.machine import load_machine, machine_from_dict
from cnc_gym.toolpath import SegmentKind

GSK = load_machine("gsk25i")  # the preset has a B axis (rotary table)


def run(text: str, machine=GSK):
    return interpret(text, machine=machine)


def test_x8_rotary_only_feed_is_degrees_per_minute():
    # X8, first block (§3.2.2): `G91 G01 B90.0 F300;` turns B by 90° at 300 deg/min: 0.3 min = 18 s.
    tp = run("G91 G01 B90.0 F300;\n")
    assert len(tp) == 1 and tp.kind[0] == SegmentKind.LINE
    assert tp.length[0] == 0.0 and np.all(tp.start[0] == tp.end[0])  # no XYZ motion
    assert tp.rotary_axes == "B"
    assert tp.rotary_start[0, 0] == 0.0 and tp.rotary_end[0, 0] == 90.0
    assert tp.feed[0] == 300.0
    assert tp.rotary_length[0] / tp.feed[0] * 60.0 == pytest.approx(18.0)


def test_x8_combined_feed_along_the_composite_vector():
    # X8, second block (§3.2.2): `G91 G01 X20.0 B40.0 F300.0;`. The manual: time = √(20² + 40²)/300 =
    # 0.14907 min (printed "0.014907", a slipped digit: its own next line divides by 0.14907), and the B
    # rate 40/0.14907 = 268.3 deg/min. So X moves at 20/0.14907 = 134.16 mm/min.
    tp = run("G91 G01 X20.0 B40.0 F300.0;\n")
    minutes = math.sqrt(20**2 + 40**2) / 300.0
    assert minutes == pytest.approx(0.14907, abs=1e-5)
    assert tp.end[0].tolist() == [20.0, 0.0, 0.0]
    assert tp.rotary_end[0, 0] == 40.0
    assert tp.path_feed[0] == pytest.approx(20.0 / minutes)
    assert tp.length[0] / tp.path_feed[0] == pytest.approx(minutes)
    b_rate = tp.path_feed[0] * 40.0 / 20.0
    assert b_rate == pytest.approx(268.3, abs=0.05)


def test_absolute_incremental_g92_and_g53():
    # G90 B is a position; G91 B a distance; G92 B10 makes the current machine angle read 10 (so B20 then
    # lies 10° further in machine terms); G53 B5 goes to machine 5° whatever the G92 origin.
    tp = run("G90 G00 B30\nG91 G00 B-5\nG90 G92 B10\nG01 X1 B20 F100\nG53 B5\nG00 B0\n")
    b = tp.rotary_end[:, 0].tolist()
    assert b == [30.0, 25.0, 35.0, 5.0, 15.0]  # G92 origin: machine 25 ↔ program 10, so program 0 = 15
    assert tp.kind.tolist() == [SegmentKind.RAPID, SegmentKind.RAPID, SegmentKind.LINE, SegmentKind.RAPID,
                                SegmentKind.RAPID]  # fmt: skip
    # the rows that do not move B hold its angle
    tp = run("G00 B30\nG01 X5 F100\nY5\n")
    assert tp.rotary_start[1:, 0].tolist() == [30.0, 30.0] and tp.rotary_end[1:, 0].tolist() == [30.0, 30.0]


def test_degrees_are_not_inches_but_the_feed_counts_them_as_inches_in_g20():
    # G20: X1 is 25.4 mm, B14 stays 14°. F10 is 10 in/min along √(1² + 14²) "inches", so X covers 1 in
    # in √197/10 min: 25.4·10/√197 mm/min.
    tp = run("G20 G01 X1 B14 F10\n")
    assert tp.end[0, 0] == pytest.approx(25.4) and tp.rotary_end[0, 0] == 14.0
    assert tp.path_feed[0] == pytest.approx(25.4 * 10 / math.sqrt(197))


def test_system_variables_read_the_rotary_axis_as_the_fourth():
    # #5004 block end (work coordinates), #5024 machine position: B is the 4th axis.
    tp = run("G92 B10\nG01 B30 F100\n#100=#5004\n#101=#5024\nG01 X#100 Y#101\n")
    assert tp.end[-1].tolist() == [30.0, 20.0, 0.0]


def test_trace_records_carry_the_rotary_angles():
    records = run("G01 X1 F100\nG91 G01 X1 B45\n").to_records()
    assert records[0]["rotary_end"] == {"B": 0.0} and "rotary_start" not in records[0]
    assert records[1]["rotary_start"] == {"B": 0.0} and records[1]["rotary_end"] == {"B": 45.0}
    # a 3-axis path has no rotary keys at all (the contract's shape is unchanged)
    assert "rotary_end" not in interpret("G01 X1 F100\n").to_records()[0]


@pytest.mark.parametrize(
    ("text", "code"),
    [
        ("G02 X1 Y1 R1 B3 F100\n", "rotary-axis-context"),  # arcs do not carry rotary axes
        ("G41 D1 G01 X10 Y0 F100\nG01 X20 B3\n", "rotary-axis-context"),  # not in cutter compensation
        ("G01 X10 ,L1 F100\nY10 B5\n", "rotary-axis-context"),  # a chamfer cannot join a rotary move
        ("G01 X10 B5 ,R1 F100\n", "rotary-axis-context"),
        ("G28 B0\n", "rotary-axis-context"),
        ("G81 X1 Z-1 R1 F100 B3\n", "rotary-axis-context"),
        ("G01 B5\n", "missing-feed"),  # a rotary-only G01 still needs F
        ("G01 A5 F100\n", "unsupported-axis"),  # the preset has B only
    ],
)
def test_rotary_words_outside_g00_g01_are_errors(text, code):
    with pytest.raises(ProgramError) as err:
        run(text)
    assert err.value.code == code


def test_a_machine_without_rotary_axes_rejects_them_by_name():
    for machine in (None, load_machine("vmc-small")):
        with pytest.raises(ProgramError) as err:
            interpret("G91 G01 X20 B40 F300\n", machine=machine)
        assert err.value.code == "unsupported-axis" and "axis B" in str(err.value)


def test_machine_config_rotary_axes_are_validated():
    from cnc_gym.errors import ConfigError

    m = machine_from_dict({"rotary_axes": {"a": {"rapid_deg_min": 7200}, "c": {}}})
    assert m.rotary_letters == "AC" and m.rotary_axes["A"].rapid_deg_min == 7200
    for bad in ({"rotary_axes": {"d": {}}}, {"rotary_axes": {"b": {"speed": 1}}},
                {"rotary_axes": {"b": {"max_accel_deg_s2": -1}}}, {"rotary_axes": [1]}):  # fmt: skip
        with pytest.raises(ConfigError):
            machine_from_dict(bad)
