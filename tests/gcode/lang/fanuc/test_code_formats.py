"""Number formats that depend on the code a word belongs to (CodeSpec.address_rules).

The L of the pocket, boss and face-milling cycles (G110-G137, G126/G127) is a step-over length (§3.4.16; every
example steps L10, and a fractional step is ordinary), while the L of M98/G65 (a repeat count) and G10 (a data
type) is a whole number without a decimal point (Table 1-1, alarm 7). G06.2's K (knot) and R (weight) are
plain numbers: test_nurbs.py.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import pytest
from gcode_helpers import program_error, records

from cnc_gym.gcode import interpret
from cnc_gym.toolpath import SegmentKind

POCKET = "G90 G17 G0 X0 Y0 Z25 F1000\nG110 X0 Y0 Z-5 R2 I10 L{L} W5 Q5 V2 D1 F500\nG80\n"


def _ring_radii(text: str) -> list[float]:
    return sorted({round(r["radius"], 6) for r in records(text, tool_offsets={"D": {1: 2.5}})
                   if r["kind"] == "arc"})  # fmt: skip


def test_pocket_step_over_takes_a_decimal_point():
    # G110: rings of radius L, 2L, … up to I - r (§3.4.16): I10, tool radius 2.5 → the last ring at 7.5.
    # L2.5 → 2.5, 5, 7.5; the whole-number L5 → 5, 7.5. With L read as an integer, L2.5 would be alarm 7.
    assert _ring_radii(POCKET.format(L="2.5")) == [2.5, 5.0, 7.5]
    assert _ring_radii(POCKET.format(L="5")) == [5.0, 7.5]
    # From an expression: not rounded to a whole number (L[5/2] = 2.5, not 3).
    assert _ring_radii("#1=5\n" + POCKET.format(L="[#1/2]")) == [2.5, 5.0, 7.5]


def test_face_milling_step_over_in_inch():
    # G126 (X64's format) in G20: L0.1 inch = 2.54 mm at most per step over J0.2 inch = 5.08 mm: two equal
    # steps, passes at Y 0, 2.54 and exactly J = 5.08 (the cycle spreads ceil(J/L) steps evenly over J).
    tp = interpret("G20\nG90 G17 G0 X0 Y0 Z1 F10\nG126 X0 Y0 Z-0.1 R0.1 I1 J0.2 L0.1 F8\n")
    ys = sorted({round(float(tp.end[n][1]), 6) for n in range(len(tp.kind))
                 if tp.kind[n] == SegmentKind.LINE and tp.end[n][2] == pytest.approx(-2.54)})  # fmt: skip
    assert ys == [0.0, 2.54, 5.08]
    # L0.075 inch: ceil(0.2 / 0.075) = 3 steps of 5.08 / 3 mm (L read as a whole number would be alarm 7).
    tp = interpret("G20\nG90 G17 G0 X0 Y0 Z1 F10\nG126 X0 Y0 Z-0.1 R0.1 I1 J0.2 L0.075 F8\n")
    ys = sorted({round(float(tp.end[n][1]), 6) for n in range(len(tp.kind))
                 if tp.kind[n] == SegmentKind.LINE and tp.end[n][2] == pytest.approx(-2.54)})  # fmt: skip
    assert ys == pytest.approx([0.0, 5.08 / 3, 2 * 5.08 / 3, 5.08], abs=1e-6)


@pytest.mark.parametrize("text", ["M98 P1000 L2.5\n", "G10 L2.5 P1 X0\n", "G65 P9000 L2.5\n"])
def test_counts_and_data_types_keep_the_whole_number_rule(text):
    err = program_error(text)
    assert err.code == "decimal-point-not-allowed" and err.alarm == 7


def test_other_codes_in_a_pocket_block_keep_their_rules():
    # The override is for L only: a T with a decimal point in the G110 block is still alarm 7.
    err = program_error("G0 X0 Y0 Z25 F100\nG110 X0 Y0 Z-5 R2 I10 L2.5 W5 Q5 V2 D1 T1.5\n")
    assert err.code == "decimal-point-not-allowed"


def test_a_later_block_of_the_modal_pocket_cycle_takes_its_step_over():
    # The block "X1 L2.5" names no code: its L belongs to the modal G110 (group 09), so L2.5 is a length
    # there (the second pocket at X1 has rings 2.5, 5, 7.5; the first, L5, has 5, 7.5). Also with an
    # expression word in the block (the scanner path).
    base = "G90 G17 G0 X0 Y0 Z25 F1000\nG110 X0 Y0 Z-5 R2 I10 L5 W5 Q5 V2 D1 F500\n"
    assert _ring_radii(base + "X1 L2.5\nG80\n") == [2.5, 5.0, 7.5]
    assert _ring_radii("#1=1\n" + base + "X#1 L2.5\nG80\n") == [2.5, 5.0, 7.5]


@pytest.mark.parametrize(("text", "line"), [
    ("G01 X1 L2.5 F100\n", 1),  # no code gives L a length format
    ("G81 X0 Y0 Z-5 R1 F100\nX1 L2.5\n", 2),  # a drilling cycle has no L
    ("G0 X0 Y0 Z25\nG110 X0 Y0 Z-5 R2 I10 L5 W5 Q5 V2 D1 F500\nG80\nX1 L2.5\n", 4),  # after G80
])  # fmt: skip
def test_l_with_a_point_outside_a_code_that_takes_it_is_still_alarm_7(text, line):
    err = program_error(text, tool_offsets={"D": {1: 2.5}})
    assert err.code == "decimal-point-not-allowed" and err.line == line
