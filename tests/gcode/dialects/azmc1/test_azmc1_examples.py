"""The worked examples of the AMK AZ-MC1 programming manual as golden tests (docs/azmc1_examples.md indexes
them: one row per example, E1-E30).

Each test runs the manual's program (comments that only repeat the block dropped; an F, a D or a dwell added
where the manual omits it, and said so) and compares the tool path with expectations worked out by hand
from the manual's text — points, centres, radii, pass counts — written out with the reasoning, never taken
from the interpreter. Where the manual contradicts itself the test follows the reading its own examples
support, and says so.
"""

from __future__ import annotations

import math

import pytest

from cnc_gym.errors import ProgramError
from cnc_gym.gcode import get_dialect, interpret
from cnc_gym.gcode.dialects.azmc1.options import AzOptions, ToolRecord
from cnc_gym.machine import load_machine
from cnc_gym.toolpath import SegmentKind

AZ = get_dialect("azmc1")


def run(text: str, **kw):
    return interpret(text, dialect=kw.pop("dialect", AZ), file=kw.pop("file", "e.nc"), **kw)


def ends(text: str, **kw) -> list[tuple[float, ...]]:
    """Segment end points rounded to 0.1 µm (the controller's resolution)."""
    return [tuple(round(c, 4) + 0.0 for c in row) for row in run(text, **kw).end.tolist()]


def error(text: str, **kw) -> ProgramError:
    with pytest.raises(ProgramError) as info:
        run(text, **kw)
    return info.value


def with_options(**options):
    from dataclasses import replace

    return replace(AZ, options=AzOptions(**options))


# ---------------------------------------------------------------------- E1-E4: structure and expressions
def test_e1_numbering_is_optional_and_changes_nothing():
    # §2.2: the same program without, with partial and with complete block numbers ("Block 1..4" are ours).
    without = "% 100\nG0 X10 Y10\nG1 Z-5 F500\nX20\nG0 Z10\nM30\n"
    partial = "% 100\nN10 G0 X10 Y10\nG1 Z-5 F500\nN30 X20\nG0 Z10\nM30\n"
    complete = "% 100\nN100 G0 X10 Y10\nN200 G1 Z-5 F500\nN300 X20\nN400 G0 Z10\nN700 M30\n"
    expected = [(10, 10, 0), (10, 10, -5), (20, 10, -5), (20, 10, 10)]
    for text in (without, partial, complete):
        assert ends(text) == expected


def test_e2_nested_comments_leave_an_empty_block():
    # §2.3.2: "(Comment (comment))" nests; N300 is then an empty block. F100 is ours.
    text = ("% 100 (Workpiece designation, date)\nN200 G1 X10 F100 (Circular pocket)\n"
            "N300 (Comment (comment))\nN800 M30\n")
    toolpath = run(text)
    assert ends(text) == [(10, 0, 0)] and toolpath.line.tolist() == [2]


def test_e3_expression_samples():
    # §2.4.1: 100, 100+20, 100+R10, 100+P10 (P10: the parameter whose number R10 holds), 100*[2+R3],
    # DEXP[2] = 10**2, 100+SIN[R10+P20]; R10 = 20 → P10 reads R20 = 3; R20 = 3 → P20 reads R3 = 0.5.
    text = ("R10 = 20 R20 = 3 R3 = 0.5\nG1 F100 X100 Y100+20 Z100+R10\nX100+P10 Y100*[2+R3] Z DEXP[2]\n"
            "X100+SIN[R10+P20]\nM30\n")
    sin_20_5 = 100 + math.sin(math.radians(20.5))
    assert ends(text) == [(100, 120, 120), (103, 250, 100), (round(sin_20_5, 4), 250, 100)]
    # R5 = [[sin[R1*30.00] + R2] / R5]: lower case, nested brackets, self-reference.
    text = "R1 = 1 R2 = 2 R5 = 5\nR5 = [[sin[R1*30.00] + R2] / R5]\nG1 X R5 F100\nM30\n"
    assert ends(text) == [((0.5 + 2) / 5, 0, 0)]


def test_e4_operator_and_function_table():
    # §2.4.1.2/§2.4.1.3 rows: 11 MOD 3 = 2; 2**R3 with R3 = 3 is 8; SQRT[SQR[R2]+SQR[R3]] with 3, 4 is 5;
    # SIN[R2 * 30 + 10] in degrees; INT cuts off, FRACT keeps the rest.
    text = ("R2 = 3 R3 = 4\nR1 = 11 MOD 3\nR4 = 2**R3\nR6 = SQRT[SQR[R2]+SQR[R3]]\nG1 F100 X R1 Y R4 Z R6\n"
            "X SIN[R2 * 30 + 10] Y INT[7.9] Z FRACT[7.25]\nM30\n")
    assert ends(text) == [(2, 16, 5), (round(math.sin(math.radians(100)), 4), 7, 0.25)]


# ---------------------------------------------------------------------- E5-E10: words, motion, dwell
def test_e5_first_example_program():
    # §2.8 example: G00 to (100, 100), Z100 still G00; N30 spindle on at 1000 and a feed to Z50 at F1000;
    # N40 a feed back; N50 rapid to (200, 200, 200); the repeated N50 is accepted.
    text = ("% 100 (Example program)\nN10 G00 X100 Y100\nN20 Z100\nN30 G1 Z50 F1000 S1000 M3\nN40 Z100\n"
            "N50 G0 X200 Y200 Z200\nN50 M5\nN60 M30\n")
    toolpath = run(text)
    assert ends(text) == [(100, 100, 0), (100, 100, 100), (100, 100, 50), (100, 100, 100), (200, 200, 200)]
    assert toolpath.line.tolist() == [2, 3, 4, 5, 6]
    assert toolpath.kind.tolist()[2:4] == [1, 1]  # lines
    assert toolpath.feed.tolist()[2:4] == [1000, 1000]
    assert toolpath.spindle_rpm.tolist() == [0, 0, 1000, 1000, 1000]


def test_e6_assignment_glued_to_a_value_is_an_error():
    # §2.6: X50R1=7 is an ERROR, X50 R1=7 is correct (and R1 is assigned before the move).
    err = error("G1 F100\nX50R1=7\n")
    assert err.code == "syntax" and err.line == 2 and err.file == "e.nc" and "X50 R1=7" in err.message
    assert ends("G1 F100\nX50 R1=7\nY R1\nM30\n") == [(50, 0, 0), (50, 7, 0)]


def test_e7_axis_values_are_expressions():
    # §2.6: X 100.0, Y 0.001, Z SIN [30] = 0.5; B 4 * R1/R2 on a machine with a rotary B (the gsk25i
    # preset); A SQRT [2]/2 on a machine without A is refused by name.
    assert ends("G1 F100 X 100.0 Y 0.001 Z SIN [30]\nM30\n") == [(100, 0.001, 0.5)]
    toolpath = run("R1 = 30 R2 = 2\nG1 F100 B 4 * R1/R2\nM30\n", machine=load_machine("gsk25i"))
    assert toolpath.rotary_end[-1].tolist() == [60.0]
    assert error("G1 F100 A SQRT [2]/2\n").code == "unsupported-axis"


def test_e8_g01_stays_in_force_through_g41_and_the_full_circle():
    # §3 modal groups: G01 persists through G41; N90 G02 X100 Y50 I100 from (100, 50) is a full circle about
    # (200, 50), r = 100. F and D1 (radius 0: the geometry as programmed) are ours.
    text = ("N50 G01 X100 Y200 F500 D1\nN60 G41 X200 Y200\nN70 X300 Y250\nN80 X100 Y50\n"
            "N90 G02 X100 Y50 I100\nN95 G40 G1 X0 Y0\nM30\n")
    toolpath = run(text)
    assert ends(text)[:5] == [(100, 200, 0), (200, 200, 0), (300, 250, 0), (100, 50, 0), (100, 50, 0)]
    assert toolpath.kind.tolist()[:5] == [1, 1, 1, 1, 2]
    assert toolpath.center[4].tolist()[:2] == [200, 50] and toolpath.radius[4] == 100
    assert math.isclose(toolpath.sweep[4], -2 * math.pi)


def test_e9_rapid_absolute_and_incremental_and_the_slave_axis():
    # §3.1.1: G00 G90 X120 Y80 ≡ G00 G91 X80 Y60 from P1 (40, 20) (the figure is lost; P1 is implied);
    # the slave axis U has no counterpart on the simulated machine and is refused by name.
    absolute = ends("G0 X40 Y20\nG00 G90 X120 Y80\nM30\n")
    incremental = ends("G0 X40 Y20\nG00 G91 X80 Y60\nM30\n")
    assert absolute == incremental == [(40, 20, 0), (120, 80, 0)]
    err = error("G0 X40 Y20\nG00 G90 X120 Y80 U90\n")
    assert err.code == "unsupported-axis" and err.line == 2


def test_e10_dwell_by_g04_and_by_time():
    # §3.1.4, §10.1: G04 X 4.13 and $TIME 4.13 both wait 4.13 s without motion.
    toolpath = run("N10 G04 X 4.13\nN10 $TIME 4.13\nM30\n")
    assert toolpath.kind.tolist() == [SegmentKind.DWELL] * 2 and toolpath.dwell_s.tolist() == [4.13, 4.13]


# ---------------------------------------------------------------------- E11-E17: homing, offsets, M
def test_e11_homing_order():
    # §3.1.5: G74 X3 Z1 Y4 homes Z, then X, then Y; equal indices home together (to the machine zero).
    assert ends("G0 X10 Y20 Z30\nG74 X3 Z1 Y4\nM30\n") == [(10, 20, 30), (10, 20, 0), (0, 20, 0), (0, 0, 0)]
    assert ends("G0 X10 Y20 Z30\nG74 X3 Z3 Y3\nM30\n") == [(10, 20, 30), (0, 0, 0)]


def test_e12_g92_datum_offset_sets_adds_and_withdraws():
    # §3.1.6: after G92 X10 Z30, X0 is absolute 10 and Z0 absolute 30; G92 X0 Z0 withdraws it; in G91 a
    # second G92 adds to the first (our variant).
    assert ends("N10 G90\nN20 G92 X10 Z30\nG0 X0 Z0\nG92 X0 Z0\nX0 Z0\nM30\n") == [(10, 0, 30), (0, 0, 0)]
    assert ends("G91 G92 X5\nG92 X5\nG90 G0 X0\nM30\n") == [(10, 0, 0)]


def test_e13_software_limits():
    # §3.1.7-§3.1.8: G98 sets the negative limits, G99 the positive ones (X+1000 parses); X1000 is on the
    # limit, X1001 beyond it.
    text = "N10 G98 X-1000 Y-2000\nN10 G99 X+1000 Y+2000\nG0 X1000 Y-2000\nG1 X1001 F100\nM30\n"
    err = error(text)
    assert err.code == "soft-limit" and err.line == 4 and "X1001" in err.message


def test_e14_spindle_sequence():
    # §4.1.7: M03 takes S over from an earlier block; S alone does not start the spindle; M19 stops it at
    # position 0. The G04 X1 dwells are ours, to see the spindle on the tool path.
    text = ("N50 S750 M03\nG04 X1\nN60 M19\nN70 M03\nG04 X1\nN80 M05\nG04 X1\nN10 S1000\nG04 X1\nN20 M03\n"
            "G04 X1\nN30 M04\nG04 X1\nN40 M05\nN99 M30\n")
    assert run(text).spindle_rpm.tolist() == [750, 0, 750, 0, 0, 1000, -1000]


def test_e15_spindle_position_axis_is_refused_by_name():
    # §4.1.7: G74 C99 and C500 F1000 need a spindle position axis C; the simulated machine has none.
    text = "N10 M03 S1000\nN20 G04 X2\nN30 M05\nN40 G74 C99\nN50 C500 F1000\nN99 M30\n"
    err = error(text)
    assert err.code == "unsupported-axis" and err.line == 4


def test_e16_synchronous_control_is_refused_by_name():
    # §4.1.8: M28 S1000 couples Z to spindle 2 (1000 µm/rev); not built, refused by name.
    text = "%1999 (Thread drilling)\nN10 G01 Z-50 F5000\nN20 M28 S1000\nN30 G60 F10000\nN999 M30\n"
    err = error(text)
    assert err.code == "not-implemented" and err.line == 3 and "M28" in err.message


def test_e17_plc_transfer_parameters():
    # §4.2: M25 S-1 copies all transfer parameters to R1000+n; M25 Sn and M112 Sn one of them.
    az = with_options(plc_transfer={1: 7.5, 2: -3.0})
    assert ends("M25 S-1\nG1 F100 X R1001 Y R1002\nM30\n", dialect=az) == [(7.5, -3, 0)]
    assert ends("M25 S2\nM112 S1\nG1 F100 X R1001 Y R1002\nM30\n", dialect=az) == [(7.5, -3, 0)]


# ---------------------------------------------------------------------- E18-E20: calls and parameters
def test_e18_local_subroutines_run_only_when_called():
    # §7.1: %L007 and %L008 before %100; the calls run L008, L007, L008; nothing runs at the file's start.
    text = ("%L007\nN1 G1 X1 Y0 F100\nN2 X1 Y1\nN9 M29\n%L008\nN11 G1 X2 Y0 F100\nN12 X2 Y2\nN19 M29\n"
            "%100\nN100 G0 X0 Y0\nN105 G0 Z1\nN110 LL008\nN200 LL007\nN250 LL008\nN300 M30\n")
    toolpath = run(text)
    assert ends(text) == [(0, 0, 1), (2, 0, 1), (2, 2, 1), (1, 0, 1), (1, 1, 1), (2, 0, 1), (2, 2, 1)]
    assert toolpath.line.tolist() == [11, 6, 7, 2, 3, 6, 7]


def test_e19_local_and_global_calls(tmp_path):
    # §7.2 (the reconstruction of the scrambled table): file "100" is a global subroutine ending with M29;
    # file "333" holds %L007 (without M29: the next % ends it) and the main program %333.
    (tmp_path / "100").write_text("%100 (Global subroutine)\nN1 G1 X5 F100\nN9 M29 (M29 must stand here)\n")
    main = tmp_path / "333"
    main.write_text("%L007 (Local subroutine)\nN11 G1 Y7 F100\nN19\n%333 (Main program)\nN100 G0 X0\n"
                    "N110 LL007\nN200 L100\nN300 M30\n")
    toolpath = interpret(main.read_text(), dialect="azmc1", file=str(main))
    assert [tuple(r) for r in toolpath.end.tolist()] == [(0, 7, 0), (5, 7, 0)]
    assert [toolpath.source(i) for i in range(2)] == [(str(main), 2), (str(tmp_path / "100"), 2)]


def test_e20_parameters_in_addresses():
    # §8: R12=0.12; XR1 (the parameter right after the letter); X R1*SIN [R2*30].
    text = "R12=0.12\nR1 = 5 R2 = 1\nG1 XR1 Y R12 F100\nX R1*SIN [R2*30]\nM30\n"
    assert ends(text) == [(5, 0.12, 0), (2.5, 0.12, 0)]


# ---------------------------------------------------------------------- E21-E27: control blocks
IF_PROGRAM = """R1 = {r1} R2 = {r2}
$IF R1
G0 Y1
$ENDIF
$IF R1 == 0
G0 X1
$ELSEIF R2>= 0.5
G0 X2
$ELSE
G0 X3
$ENDIF
$IF R1 > R2
G0 Z1
$ELSE
G0 Z2
$ENDIF
M30
"""


@pytest.mark.parametrize(("r1", "r2", "end"), [
    (0.49, 0.5, (2, 0, 2)),  # |0.49| < 0.5: false; R2 >= 0.5; 0.49 > 0.5 false
    (0.5, 0.5, (2, 1, 2)),  # |0.5| >= 0.5: true
    (-0.5, 0.5, (2, 1, 2)),  # |-0.5| >= 0.5: true
    (0, 0.5, (1, 0, 2)),  # R1 == 0
    (0.49, 0.25, (3, 0, 1)),  # the $ELSE branch; 0.49 > 0.25
])  # fmt: skip
def test_e21_if_elseif_else_and_truth(r1, r2, end):
    # §9.1.1: $IF R1 runs when |R1| >= 0.5; $IF … $ELSEIF … $ELSE … $ENDIF.
    assert ends(IF_PROGRAM.format(r1=r1, r2=r2))[-1] == end


def test_e22_a_negative_literal_after_a_comparison_must_be_bracketed():
    # §9.1.1 note: $IF R1 >= -5 is wrong, $IF R1 >= [-5] is right.
    err = error("R1 = 1\n$IF R1 >= -5\nG0 X1\n$ENDIF\n")
    assert err.code == "syntax" and err.line == 2 and "[-5]" in err.message
    assert ends("R1 = 1\n$IF R1 >= [-5]\nG0 X1\n$ENDIF\nM30\n") == [(1, 0, 0)]


SWITCH_PROGRAM = """R1 = {r1} R2 = {r2} R3 = 1
N100 $SWITCH INT [R1*R2/R3]
$CASE 1
N120 G0 X1
N130 G0 Y1
$BREAK
$CASE R2
N160 G0 X2
$BREAK
$CASE 5
N320 G0 X5
$BREAK
$DEFAULT
N360 G0 X9
N380 G0 Y9
$ENDSWITCH
M30
"""


@pytest.mark.parametrize(("r1", "r2", "end"), [
    (1, 1, [(1, 0, 0), (1, 1, 0)]),  # INT[1] = 1: N120-N130
    (1, 3, [(3 - 1, 0, 0)]),  # INT[3] = 3 = R2: N160 (X2)
    (5, 1, [(5, 0, 0)]),  # INT[5] = 5: N320 (the duplicate N320 of the manual is ours to drop)
    (2.7, 3, [(9, 0, 0), (9, 9, 0)]),  # INT[8.1] = 8: $DEFAULT
])  # fmt: skip
def test_e23_switch_case_default(r1, r2, end):
    # §9.1.2: $SWITCH INT [R1*R2/R3] with $CASE 1, $CASE R2, $CASE 5, $DEFAULT; $BREAK leaves the switch.
    assert ends(SWITCH_PROGRAM.format(r1=r1, r2=r2)) == end


def test_e24_for_loop_runs_46_passes():
    # §9.2: $FOR R1 = 10, 100, 2 runs R1 = 10, 12, …, 100 (the end included: C's for(;R1<=100;)): 46
    # passes of an X and a Y move; the last is X = sin 500°, Y = cos 500°. F1000 is ours.
    text = "G1 F1000\nN100 $FOR R1= 10, 100, 2\nN110 X SIN [R1 * 5]\nN120 Y COS [R1 * 5]\n$ENDFOR\nM30\n"
    points = ends(text)
    assert len(points) == 2 * 46
    assert points[-1] == (round(math.sin(math.radians(500)), 4), round(math.cos(math.radians(500)), 4), 0)


def test_e25_while_loop_runs_67_passes():
    # §9.3: R1 = 100, minus 1.5 while R1 > 0.5: after k passes R1 = 100 - 1.5 k; the last pass is k = 67
    # (R1 = 1 > 0.5 before it), ending at R1 = Y = -0.5. The assignment runs before Y R1 in its block.
    text = "N90 R1 = 100.0\nG1 F1000\nN100 $WHILE R1 > 0.5\nN110 R1 = R1 - 1.5 Y R1\nN120 $ENDWHILE\nM30\n"
    points = ends(text)
    assert len(points) == 67 and points[0] == (0, 98.5, 0) and points[-1] == (0, -0.5, 0)


def test_e26_do_loop_runs_167_passes():
    # §9.4: R1 = 100, minus 0.6 until R1 >= R3 fails: with R3 = 0 (the manual leaves R3 unset) the last
    # pass is k = 167 (100 - 0.6·166 = 0.4 >= 0), ending at R1 = Y = -0.2.
    text = "N90 R1 = 100.0 R3 = 0\nG1 F1000\nN100 $DO\nN110 R1 = R1 - .6 Y R1\nN120 $ENDDO R1 >= R3\nM30\n"
    points = ends(text)
    assert len(points) == 167 and points[-1] == (0, -0.2, 0)


def test_e27_break_and_continue():
    # §9.4.1/§9.4.2 skeletons with bodies of ours: $BREAK leaves the endless $WHILE after the third pass;
    # $CONTINUE skips the even R1 of $FOR R1 = 1, 6, 1 (the increment still runs).
    text = "R1 = 0\nG1 F100\n$WHILE 1\nR1 = R1 + 1\nX R1\n$IF R1 >= 3\n$BREAK\n$ENDIF\n$ENDWHILE\nM30\n"
    assert ends(text) == [(1, 0, 0), (2, 0, 0), (3, 0, 0)]
    text = "G1 F100\n$FOR R1 = 1, 6, 1\n$IF R1 MOD 2 == 0\n$CONTINUE\n$ENDIF\nX R1\n$ENDFOR\nM30\n"
    assert ends(text) == [(1, 0, 0), (3, 0, 0), (5, 0, 0)]


# ---------------------------------------------------------------------- E28-E30: tool offsets and tools
TLO_TRO = """N30 G0 D0 X0 Y0 Z0 G17
N40 G0 D10 X10 Y10
N50 G1 Z100 F1000
N60 G41
N70 G1 Z0
N80 G2 X10 Y10 I-15
N90 G0 Z100
N100 D20
N110 G1 Z0
N120 G1 X20 Y20
N130 G02 X10 Y10 I-15
N140 G0 Z100
N150 G40 G0 X0 Y0
M30
"""


def test_e28_tool_offset_example_as_printed_and_repaired():
    # §11.4 (G17): as printed, the first move in the plane after G41 is the circle N80: TRO selection on a
    # circle is an error (§11.3.1). "N100 D2 D20" is garbled: read N100 D20. The F of N50 carries on.
    offsets = {"H": {10: 20.0, 20: 30.0}, "D": {10: 5.0, 20: 6.0}}
    err = error(TLO_TRO, tool_offsets=offsets)
    assert err.code == "comp-arc-startup" and err.line == 6
    # Without N60 (no TRO): the length of D10 (20) comes with the Z travel of N50, not with N40; D20's (30)
    # with N110; N80 is a full circle r = 15 about (-5, 10); N130 from (20, 20) with I-15 has its centre at
    # (5, 20), start radius 15 and end radius |(10, 10) - (5, 20)| = 11.18: the circle error.
    repaired = TLO_TRO.replace("N60 G41\n", "").replace("N150 G40 G0", "N150 G0")
    err = error(repaired, tool_offsets=offsets)
    assert err.code == "arc-radius-mismatch" and err.line == 10
    before = repaired.split("N130")[0] + "M30\n"
    toolpath = run(before, tool_offsets=offsets)
    assert ends(before, tool_offsets=offsets) == [(10, 10, 0), (10, 10, 120), (10, 10, 20), (10, 10, 20),
                                                  (10, 10, 120), (10, 10, 30), (20, 20, 30)]  # fmt: skip
    assert toolpath.center[3].tolist()[:2] == [-5, 10] and toolpath.radius[3] == 15


def test_e29_tool_data_functions_and_breakage():
    # §12.1-§12.2: R1=TALT[R2] (D2's sister is D5), M06 TTLOC[R1] (D5 sits in location 12), M06 TTLOC[4]
    # (not in the table: its own location 4). Breakage: M112 then $IF R1001 == 1 / TRESDEL[R1]: the manual
    # writes M112 S1001, which by its own rule (R1000+n) fills R2001; we read it as S1 (→ R1001).
    tools = {2: ToolRecord(alternative=5), 5: ToolRecord(life=100, residual=40, location=12)}
    az = with_options(tools=tools, plc_transfer={1: 1})
    text = ("R2 = 2\nR1=TALT[R2]\nM06 TTLOC[R1]\nG1 X1 F100\nM06 TTLOC[4]\nX2\nR9 = TRES[R1]\nY R9\nM112 S1\n"
            "$IF R1001 ==1\nTRESDEL[R1]\n$ENDIF\nR9 = TRES[R1]\nY R9\nM30\n")
    toolpath = run(text, dialect=az)
    assert ends(text, dialect=az) == [(1, 0, 0), (2, 0, 0), (2, 40, 0), (2, 0, 0)]
    assert toolpath.tool.tolist() == [12, 4, 4, 4]


SISTER = """%999999
$IF TRES[R1] <= 0
R1=TALT[R1]
$IF R1 == 0
M80
M30
$ENDIF
$IF TRES[R1] <=0
M30
$ENDIF
$ENDIF
DR1 M06 T[TLOC[R1]]
M29
"""


@pytest.mark.parametrize(("tools", "expected"), [
    ({2: ToolRecord(residual=10, location=7)}, ("ok", 7)),  # D2 still has life: T = TLOC[2]
    ({2: ToolRecord(residual=0, alternative=3), 3: ToolRecord(residual=5, location=9)}, ("ok", 9)),
    ({2: ToolRecord(residual=0, alternative=0)}, ("error", "unknown-code")),  # no sister: M80 to the PLC
    ({2: ToolRecord(residual=0, alternative=3), 3: ToolRecord(residual=0)}, ("end", None)),  # both worn
])  # fmt: skip
def test_e30_alternative_tool_subroutine(tmp_path, tools, expected):
    # §12.3: %1000 sets R1 = 2 and calls L999999, which switches to the sister tool when the residual life is
    # used up. The garbled nesting is repaired as above; "$IF R1=0" is read "$IF R1 == 0"; M80 ("message to
    # the PLC") is machine-specific and refused by name; M30 in the subroutine ends the whole program.
    (tmp_path / "999999").write_text(SISTER)
    main = tmp_path / "1000"
    main.write_text("%1000\nR1=2\nL999999\nG1 X1 F100\nM30\n")
    az = with_options(tools=tools)
    if expected[0] == "error":
        err = error(main.read_text(), dialect=az, file=str(main))
        assert err.code == expected[1] and err.file == str(tmp_path / "999999") and err.line == 5
        return
    toolpath = interpret(main.read_text(), dialect=az, file=str(main))
    if expected[0] == "end":
        assert len(toolpath) == 0
    else:
        assert toolpath.tool.tolist() == [expected[1]]
