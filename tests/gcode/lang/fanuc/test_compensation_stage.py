"""lang/fanuc/compensation/stage.py: the OffsetStage implements the output protocol (``canonical.Output``)
member by member, so what goes through it once it is installed (G43 in G91, G41/G42, G45-G48) reaches the
tool path as it would without it: rotary axes, NURBS segments, dwells, the segment context."""

from __future__ import annotations

import typing

import numpy as np
import pytest
from gcode_helpers import program_error

from cnc_gym.gcode import interpret
from cnc_gym.gcode.canonical import CanonicalMachine, Output
from cnc_gym.gcode.lang.fanuc.compensation.stage import OffsetStage
from cnc_gym.machine import load_machine
from cnc_gym.toolpath import SegmentKind, ToolpathBuilder

#: ``G91 G43 H1 Z0`` with H1 = 5: the stage is installed (the move carries the vector), then G90.
INSTALL = "G91 G43 H1 Z0\nG90\n"
OFFSETS = {"H": {1: 5.0}}


def _members(protocol: type) -> set[str]:
    names = set(typing.get_type_hints(protocol))
    names |= {name for name, value in vars(protocol).items() if not name.startswith("_") and
              (callable(value) or isinstance(value, property))}  # fmt: skip
    return names


def test_the_stage_defines_every_member_of_the_output_protocol_itself():
    members = _members(Output)
    assert {"position", "rotary", "rotary_next", "line", "straight_feed", "nurbs_feed", "dwell"} <= members
    assert "__getattr__" not in vars(OffsetStage)  # nothing is forwarded to the machine by name
    stage = OffsetStage(CanonicalMachine(ToolpathBuilder()))
    for name in sorted(members):
        assert name in vars(stage) or name in vars(OffsetStage) or hasattr(stage, name), name


def test_a_rotary_move_goes_through_the_installed_stage():
    """The stage used to forward unknown reads to the machine but kept writes to itself: ``rotary_next``
    stayed on the stage and the B moves were lost once G43 had installed it."""
    machine = load_machine("gsk25i")  # a B axis
    plain = interpret("G01 X10 B30 F100\nB40\n", machine=machine, tool_offsets=OFFSETS)
    staged = interpret(INSTALL + "G01 X10 B30 F100\nB40\n", machine=machine, tool_offsets=OFFSETS)
    assert plain.rotary_end.tolist() == [[30.0], [40.0]]
    rows = staged.kind != SegmentKind.RAPID  # the G43 move itself
    assert staged.rotary_end[rows].tolist() == [[30.0], [40.0]]
    assert np.allclose(staged.end[rows], plain.end + np.array([0.0, 0.0, 5.0]))


def test_rotary_words_stay_refused_in_cutter_compensation_and_work_after_g40():
    machine = load_machine("gsk25i")
    err = program_error("G10 L12 P1 R2\nG41 D1 G01 X10 F100\nG01 X20 B30\n", machine=machine)
    assert err.code == "rotary-axis-context" and err.line == 3
    tp = interpret("G10 L12 P1 R2\nG41 D1 G01 X10 Y0 F100\nX20\nG40 X30\nB15\n", machine=machine)
    assert tp.rotary_end[-1].tolist() == [15.0] and tp.end[-1].tolist() == [30.0, 0.0, 0.0]


def test_a_nurbs_curve_goes_through_the_installed_stage():
    curve = ("G05 P10000\nG00 X10 Y0 Z0\nG06.2 P2 K0 X10 Y0 F600\nK0 X10 Y10\nK0.5 X0 Y10\nK1\nK1\nG05 P0\n"
             "G01 X-5\n")
    plain = interpret(curve)
    staged = interpret(INSTALL + curve, tool_offsets=OFFSETS)
    row = int(np.flatnonzero(staged.kind == SegmentKind.NURBS)[0])
    assert np.allclose(staged.nurbs[row].control_points[:, 2], 5.0)
    base = int(np.flatnonzero(plain.kind == SegmentKind.NURBS)[0])
    assert np.allclose(staged.nurbs[row].control_points[:, :2], plain.nurbs[base].control_points[:, :2])
    assert staged.end[-1].tolist() == [-5.0, 10.0, 5.0]  # the next move starts from the curve's end


@pytest.mark.parametrize("text", ["G04 P500\nG01 X5 F100\n", "G01 X5 F100\nG04 X1\nG00 Z3\n"])
def test_dwells_and_the_segment_context_go_through_the_installed_stage(text):
    plain = interpret("M03 S900\nT2\n" + text, tool_offsets=OFFSETS)
    staged = interpret(INSTALL + "M03 S900\nT2\n" + text, tool_offsets=OFFSETS)
    rows = staged.line > 2
    assert staged.kind[rows].tolist() == plain.kind.tolist()
    assert staged.dwell_s[rows].tolist() == plain.dwell_s.tolist()
    assert staged.tool[rows].tolist() == plain.tool.tolist()
    assert staged.spindle_rpm[rows].tolist() == plain.spindle_rpm.tolist()
    assert (staged.line[rows] - 2).tolist() == plain.line.tolist()
