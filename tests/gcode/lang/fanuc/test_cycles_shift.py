"""G76/G87 shift forms and G87's two variants (cycles.py), the hole patterns' refusal of the special
cycles, and the cycle parameters' validation.

Expected paths are written out by hand from the manual's text (the figures are lost):

* §3.4.3: "The tool offset can be set by addresses I and J at the hole bottom. X and Y axes move in the
  linear interpolation, which is set by parameter 022 BIT6 (SIJ), Q is replaced by the incremental value
  specified by I and J ... the feedrate is same as the speed specified by F code. In the canned cycle
  mode, I and J are modal values. Commanding I and J can't complete machining the hole, but just
  specifies I and J again." So with SIJ: shift = (I, J) as an X/Y increment, shift and shift back are
  cutting moves at F, Q shifts nothing, I/J stay until G80, an I/J-only block bores nothing.
* §3.4.11 (G87 "canned cycle I"): at the bottom the spindle stops and the control enters feed hold;
  the operator retracts; cycle start returns to the initial level / R by G98/G99 and the spindle turns
  CW. Modelled like G88: a 0 s exact-stop dwell recorded as a feed hold, then a rapid to the return level.

The machine starts at the machine origin, so the initial level is Z0 unless a block moves Z first.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
from gcode_helpers import close, program_error, success_share, tally
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.gcode import interpret, read_program
from cnc_gym.gcode.dialects.gsk25i import DIALECT
from cnc_gym.gcode.interpreter import Interpreter
from cnc_gym.gcode.settings import CycleParameters
from cnc_gym.toolpath import SegmentKind, SegmentMode

SIJ = replace(DIALECT, cycle_params=replace(DIALECT.cycle_params, shift_by_ij=True))
G87_I = replace(DIALECT, cycle_params=replace(DIALECT.cycle_params, g87_variant=1))
_KINDS = {SegmentKind.RAPID: "rapid", SegmentKind.LINE: "line", SegmentKind.ARC: "arc",
          SegmentKind.DWELL: "dwell"}  # fmt: skip


def path(tp) -> list[tuple]:
    """(kind, end rounded to 1e-6) per segment; dwells as ("dwell", seconds)."""
    out = []
    for n in range(len(tp.kind)):
        kind = _KINDS[SegmentKind(int(tp.kind[n]))]
        if kind == "dwell":
            out.append(("dwell", float(tp.dwell_s[n])))
        else:
            out.append((kind, tuple(round(float(c), 6) + 0.0 for c in tp.end[n])))
    return out


# ------------------------------------------------------------------ G76 with 022#6 SIJ
def test_g76_sij_shifts_by_i_j_at_the_feed_and_ignores_q_for_the_shift():
    """The X33 hole with Q5 and I-3. J4.: Q is replaced by I/J, so the shift is (-3, +4) (not +X 5), cut
    at F120 both ways; the retract between them stays a rapid with the spindle stopped; M03 after."""
    tp = interpret("M3 S500;\nG90 G99 G76 X300. Y-250. Z-150. R-100. Q5 I-3. J4. P1000 F120;\n", dialect=SIJ)
    assert path(tp) == [
        ("rapid", (300, -250, 0)), ("rapid", (300, -250, -100)), ("line", (300, -250, -150)),
        ("dwell", 1.0), ("dwell", 0.0),                       # P1000, then the oriented stop
        ("line", (297, -246, -150)),                          # shift by (I, J) at the bottom
        ("rapid", (297, -246, -100)),                         # G99: out to R, shifted
        ("line", (300, -250, -100))]  # shift back               # fmt: skip
    shift, back = 5, 7
    assert close(float(tp.feed[shift]), 120.0) and close(float(tp.feed[back]), 120.0)
    assert float(tp.spindle_rpm[shift]) == 0.0 and float(tp.spindle_rpm[back]) == 0.0
    assert SegmentMode.EXACT_STOP & SegmentMode(int(tp.modes[4]))


def test_g76_sij_i_j_are_modal_an_i_j_block_only_stores_and_g80_clears_them():
    """Hole 2 reuses (I-3, J4). `I1.;` bores nothing (§3.4.3) and changes I only: hole 3 shifts (1, 4).
    After G80 a new G76 with only I2. shifts (2, 0): J was cleared with the other hole data."""
    text = ("G90 G99 G76 X0 Y0 Z-10. R-2. I-3. J4. F100;\n"
            "X10.;\n"
            "I1.;\n"
            "X20.;\n"
            "G80;\n"
            "G99 G76 X30. Y0 Z-10. R-2. I2. F100;\n")  # fmt: skip
    tp = interpret(text, dialect=SIJ)
    lines = [(int(tp.line[n]), e) for n, (k, e) in enumerate(path(tp)) if k == "line" and e[2] == -10]
    bottoms = [e for ln, e in lines]
    # Each hole: the feed to the bottom, then the shift line at the bottom.
    assert bottoms == [(0, 0, -10), (-3, 4, -10), (10, 0, -10), (7, 4, -10), (20, 0, -10), (21, 4, -10),
                       (30, 0, -10), (32, 0, -10)]  # fmt: skip
    assert all(ln != 3 for ln, _ in lines)  # the I1. block bored nothing


def test_sij_q_stays_the_modal_peck_depth_of_g73():
    """Q is shared with G73/G83 (§3.4.3): with SIJ, G76's Q5 shifts nothing but G73 in the next block pecks
    by it from R-2: feeds to -7, -12, then the bottom -15 (retracts of d = 0.5 between)."""
    tp = interpret("G90 G99 G76 X0 Y0 Z-10. R-2. Q5 I1. F100;\nG73 X10. Z-15.;\nG80;\n", dialect=SIJ)
    feeds = [e[2] for k, e in path(tp) if k == "line" and e[0] == 10]
    assert feeds == [-7, -12, -15]


def test_sij_shift_keeps_its_length_under_scaling_but_turns_with_rotation():
    """G51 P2 doubles the levels and positions (X10 → 20 before the turn), G68 R90 turns +X onto +Y.
    The programmed increment I2 turns with the map (+X → +Y) but is not scaled (§3.2.17): the machine
    shift is +2 in Y."""
    text = "G68 X0 Y0 R90;\nG51 X0 Y0 Z0 P2;\nG90 G99 G76 X10 Y0 Z-10. R-2. I2 F120;\nG80;\n"
    assert path(interpret(text, dialect=SIJ)) == [
        ("rapid", (0, 20, 0)), ("rapid", (0, 20, -4)), ("line", (0, 20, -20)), ("dwell", 0.0),
        ("line", (0, 22, -20)), ("rapid", (0, 22, -4)), ("line", (0, 20, -4))]  # fmt: skip


def test_sij_i_j_in_inch_mode_are_scaled():
    """G20: I0.1 is 2.54 mm."""
    got = path(interpret("G20 G90 G98 G76 X1. Y0 Z-1. R-0.1 I0.1 F10;\n", dialect=SIJ))
    assert got[:5] == [("rapid", (25.4, 0, 0)), ("rapid", (25.4, 0, -2.54)), ("line", (25.4, 0, -25.4)),
                       ("dwell", 0.0), ("line", (27.94, 0, -25.4))]  # fmt: skip


def test_sij_with_the_drilling_axis_following_the_plane():
    """FXY = 1, G18: the drilling axis is Y, so I (X) is an in-plane shift: bottom Y-20, shift X +1.5,
    rapid out to the initial Y0 (G98), shift back at F. J would shift along the drilling axis: alarm 61."""
    dialect = replace(SIJ, cycle_params=replace(SIJ.cycle_params, drilling_axis_follows_plane=True))
    got = path(interpret("G18 G90 G98 G76 X10 Z5 Y-20 R-2 I1.5 F100;\n", dialect=dialect))
    assert got == [("rapid", (10, 0, 5)), ("rapid", (10, -2, 5)), ("line", (10, -20, 5)), ("dwell", 0.0),
                   ("line", (11.5, -20, 5)), ("rapid", (11.5, 0, 5)), ("line", (10, 0, 5))]  # fmt: skip
    err = program_error("G18 G90 G98 G76 X10 Z5 Y-20 R-2 J1 F100;\n", dialect=dialect)
    assert err.code == "cycle-argument" and err.alarm == 61


@pytest.mark.parametrize("text", [
    "G90 G76 X0 Y0 Z-10 R-2 I1 F100;\n",
    "G90 G87 X0 Y0 Z-10 R-20 J1 F100;\n",
    "G90 G99 G76 X0 Y0 Z-10 R-2 Q1 F100;\nJ2;\n",   # in a modal block too
])  # fmt: skip
def test_without_sij_i_j_mean_nothing_to_g76_g87(text):
    err = program_error(text)
    assert err.code == "unused-word" and "SIJ" in str(err)


def test_i_j_still_mean_nothing_to_the_other_drilling_cycles_with_sij():
    assert program_error("G90 G81 X0 Y0 Z-5 R1 I3 F10;\n", dialect=SIJ).code == "unused-word"


_coord = st.integers(-400, 400).map(lambda v: v / 8.0)  # steps of 0.125 mm, exact in binary


@success_share(0.1)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(code=st.sampled_from(["G76", "G87"]), ret=st.sampled_from(["G98", "G99"]),
       hole=st.tuples(_coord, _coord), levels=st.tuples(_coord, _coord),
       shift=st.tuples(st.one_of(st.none(), _coord), st.one_of(st.none(), _coord)),
       q=st.one_of(st.none(), _coord))  # fmt: skip
def test_random_sij_boring_blocks_move_sideways_only_by_the_i_j_shift_at_f(code, ret, hole, levels, shift, q):
    """Any SIJ G76/G87 block from Z0: a ProgramError (levels the wrong way round), or a path whose only
    sideways moves after the positioning are cutting moves at F of exactly ±(I, J) (0 where omitted) —
    Q never shifts — and which ends over the hole, at the initial level (G98, G87) or R (G76 G99)."""
    words = f"X{hole[0]} Y{hole[1]} Z{levels[0]} R{levels[1]}"
    words += "".join(f" {letter}{v}" for letter, v in zip("IJ", shift, strict=True) if v is not None)
    words += f" Q{q}" if q is not None else ""
    try:
        tp = interpret(f"G90 {ret} {code} {words} F150;\n", dialect=SIJ)
    except ProgramError as err:
        assert err.code == "cycle-levels"
        bottom, r_level = levels
        assert (bottom >= r_level) if code == "G76" else (bottom <= r_level)
        tally(False)
        return
    tally(True)
    si, sj = (v or 0.0 for v in shift)
    start = 1 if (hole[0], hole[1]) != (0.0, 0.0) else 0  # the positioning rapid (dropped when zero-length)
    for n in range(start, len(tp.kind)):
        dx, dy = (float(tp.end[n][a] - tp.start[n][a]) for a in range(2))
        if math.hypot(dx, dy) > 1e-9:
            assert tp.kind[n] == SegmentKind.LINE and close(float(tp.feed[n]), 150.0)
            assert close((abs(dx), abs(dy)), (abs(si), abs(sj)))
            assert float(tp.end[n][2]) == float(tp.start[n][2])  # a level move
    end = [float(c) for c in tp.end[-1]]
    back = levels[1] if (code == "G76" and ret == "G99") else 0.0
    assert close(end, [hole[0], hole[1], back])


# ------------------------------------------------------------------ G87 back boring with SIJ
def test_g87_back_boring_with_sij_shifts_by_i_j_at_the_feed():
    """X41's numbers with I-5. instead of Q5.: at the initial level orient, shift to X295 at F120, rapid
    down to R-150 under the part, shift back at F, feed up to Z-120, dwell 1 s, orient, shift at F, rapid
    up to the initial level, shift back at F (§3.4.11: the shift as in G76)."""
    tp = interpret("M3 S500;\nG90 G99 G87 X300. Y-250. Z-120. R-150. I-5. P1000 F120;\n", dialect=SIJ)
    assert path(tp) == [
        ("rapid", (300, -250, 0)), ("dwell", 0.0), ("line", (295, -250, 0)), ("rapid", (295, -250, -150)),
        ("line", (300, -250, -150)), ("line", (300, -250, -120)), ("dwell", 1.0), ("dwell", 0.0),
        ("line", (295, -250, -120)), ("rapid", (295, -250, 0)), ("line", (300, -250, 0))]  # fmt: skip
    assert float(tp.spindle_rpm[5]) == 500.0 and float(tp.spindle_rpm[2]) == 0.0


# ------------------------------------------------------------------ G87 variant I (manual retract)
def test_g87_variant_i_feed_hold_then_operator_retract():
    """Variant I (§3.4.11) on a normal hole (Z below R): rapid to R, feed to Z, dwell P (the example's
    "stop at point Z for 1s"), spindle stop, feed hold, the operator retract modelled as a rapid to the
    return level (G99: R; G98: initial), spindle CW again. Q is stored, nothing shifts."""
    text = "M3 S500;\nG90 G99 G87 X300. Y-250. Z-150. R-120. Q5. P1000 F120;\nG98 Y-550.;\nG80;\n"
    interp = Interpreter(read_program(text), G87_I)
    tp = interp.run()
    assert path(tp) == [
        ("rapid", (300, -250, 0)), ("rapid", (300, -250, -120)), ("line", (300, -250, -150)),
        ("dwell", 1.0), ("dwell", 0.0), ("rapid", (300, -250, -120)),
        ("rapid", (300, -550, -120)), ("line", (300, -550, -150)),   # already at R: no move to R
        ("dwell", 1.0), ("dwell", 0.0), ("rapid", (300, -550, 0))]  # fmt: skip
    holds = [stop for stop in interp.state.stops if stop[1] == "feed_hold"]
    assert holds == [(2, "feed_hold"), (3, "feed_hold")]
    assert float(tp.spindle_rpm[5]) == 0.0 and float(tp.spindle_rpm[6]) == 500.0  # stopped, then CW
    assert interp.state.spindle_orients == 0  # no oriented stop in variant I


def test_g87_variant_i_needs_z_below_r_and_variant_ii_above():
    """The level rule follows the variant: X41 (Z-120 above R-150) is back boring only."""
    x41 = "G90 G87 X0 Y0 Z-120. R-150. Q5 F120;\n"
    err = program_error(x41, dialect=G87_I)
    assert err.code == "cycle-levels" and err.alarm == 61
    assert len(interpret(x41).kind) > 0
    assert program_error("G90 G87 X0 Y0 Z-150. R-120. Q5 F120;\n").code == "cycle-levels"


# ------------------------------------------------------------------ patterns and special cycles
def test_hole_pattern_refuses_a_modal_special_cycle():
    """§3.6.6: G110-G137 have no continuous-drilling function, so a pattern while G110 is modal is an
    error rather than a pocket per hole; after G80 and a standard cycle the same pattern drills."""
    pocket = "G90 G00 Z10;\nG99 G110 X0 Y0 R5 Z-10 I30 W5 Q5 L10 V2 D0 F500;\n"
    err = program_error(pocket + "G120 X0 Y0 I50 J0 K2;\n")
    assert err.code == "cycle-conflict" and err.alarm == 61 and err.line == 3
    tp = interpret(pocket + "G80;\nG81 Z-5 R1 F100 K0;\nG120 X0 Y0 I50 J0 K2;\n")
    got = path(tp)
    bottoms = [got[n][1][:2] for n in range(len(got)) if got[n][0] == "line" and tp.line[n] == 5]
    assert bottoms == [(50, 0), (-50, 0)]  # radius 50 from angle 0, two holes 180° apart


# ------------------------------------------------------------------ parameters
@pytest.mark.parametrize("kw", [{"shift_direction": 4}, {"shift_direction": -1}, {"g87_variant": 3}])
def test_cycle_parameters_out_of_range_are_config_errors(kw):
    with pytest.raises(ConfigError):
        CycleParameters(**kw)
