"""Canned cycles while cutter compensation G41/G42 is in force (manual §3.4.1: "In the canned cycle mode,
the tool offset is ignored"; §3.4).

The compensation is suspended for each cycle block as for G53/G27-G30 (compensation.py): the last
compensated block ends with its vector perpendicular to it, the cycle drills at the programmed hole
positions, and the first move in the plane after G80 starts the compensation up again (type A).
D1 = 5 mm, G17, G41 (tool on the left of the travel).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

from gcode_helpers import close

from cnc_gym.gcode import interpret

D = {"D": {1: 5.0}}


def _path(text: str):
    return [(r["line"], r["kind"], r.get("end")) for r in interpret(text, tool_offsets=D).to_records()]


def test_holes_are_drilled_at_the_programmed_positions_and_compensation_resumes():
    text = ("G17 G90 G00 X0 Y0 Z10\nG41 D1 G01 X10 Y0 F100\nG81 X20 Y0 Z-5 R2 F100\nX30\nG80\n"
            "G01 X40 Y0\nX50 Y10\nG40 X60\n")  # fmt: skip
    path = _path(text)
    # Start-up (type A): the line ends with the vector perpendicular to it: (10, 0) + 5·(0, 1).
    assert path[1] == (2, "line", [10.0, 5.0, 10.0])
    # The cycle block: no look-ahead past it, so that vector stays; the holes are at X20 and X30 on Y0
    # (uncompensated): rapid over the hole, rapid to R2, feed to Z-5, rapid back to the initial Z10.
    drilling = [p for p in path if p[0] in (3, 4)]
    assert [p[2] for p in drilling] == [[20, 0, 10], [20, 0, 2], [20, 0, -5], [20, 0, 10],
                                        [30, 0, 10], [30, 0, 2], [30, 0, -5], [30, 0, 10]]  # fmt: skip
    # After G80 the G01 X40 Y0 starts up again. Its end is the inner-corner intersection with the next
    # block (X50 Y10, a 45° left turn: inner for G41): the offset line y = 5 meets the 45° line shifted by
    # 5 to its left, y = x - 40 + 5·√2, at x = 40 + 5 - 5·√2.
    line6 = next(p for p in path if p[0] == 6)
    assert close(line6[2], [45.0 - 5.0 * math.sqrt(2), 5.0, 10.0])


def test_pattern_positions_are_not_compensated():
    # G120 (bolt circle) with no modal cycle only positions; in G41 the points are the programmed ones:
    # centre (50, 50), radius 20, first angle 0°, 4 holes 90° apart.
    text = "G17 G90 G00 X0 Y0 Z10\nG41 D1 G01 X10 Y0 F100\nG120 X50 Y50 I20 J0 K4\n"
    ends = [p[2] for p in _path(text) if p[0] == 3]
    assert len(ends) == 4
    for end, expected in zip(ends, [(70, 50), (50, 70), (30, 50), (50, 30)], strict=True):
        assert close(end[:2], expected)
