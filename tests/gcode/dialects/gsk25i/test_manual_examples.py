"""Worked examples of the GSK 25i manual (docs/gsk25i_examples.md) that had no test of their own, and the
six-hole canned-cycle examples transcribed whole (with their closing reference return), as tool paths.

docs/gsk25i_examples.md indexes every example X1-X80 and the tests that check it. The expected paths here
are worked out by hand from the manual's text and the canned cycles' step lists (§3.4; docs/gcode.md
"Canned cycles"), never taken from the code under test. The simulated machine starts
at the machine origin with every offset zero, so the work and machine coordinates agree unless an example
sets an offset, and the initial level of the canned cycles is Z0.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from gcode_helpers import close, records

from cnc_gym.gcode import get_dialect, read_program
from cnc_gym.gcode.interpreter import Interpreter


# ---------------------------------------------------------------------------------------- X2, X3, X16, X20
def test_x2_power_on_mode_is_g00():
    """X2, second program (§2.4): ``O00001; X100 Y100; G1 X0 Y0 F100;``. The first block has no
    motion code: the power-on mode G00 (Table 3-1) makes it a rapid to (100, 100); then a line back to the
    origin at F100. The O line is a program number, not motion."""
    got = records("O00001\nX100 Y100\nG1 X0 Y0 F100\n")
    assert [(r["kind"], r["start"], r["end"]) for r in got] == [
        ("rapid", [0.0, 0.0, 0.0], [100.0, 100.0, 0.0]),
        ("line", [100.0, 100.0, 0.0], [0.0, 0.0, 0.0]),
    ]  # fmt: skip
    assert "feed" not in got[0] and got[1]["feed"] == 100.0


@pytest.mark.parametrize("text", [
    "G00 X50.123\n",        # the plain word
    "G00 X 50.123\n",       # spaces are allowed anywhere, also inside the number (§1)
    "G00 X+50.123\n",       # an explicit plus sign
    "G91 G00 X50.123\n",    # from the origin, incremental gives the same point
])  # fmt: skip
def test_x3_position_x_to_50_123(text):
    """X3 (§1.3.2): "with the following command the tool can be positioned to 50.123 mm along X"; the
    format box is lost. 50.123 has three decimals, within the least increment 0.0001 mm (§3.2.19), so the
    truncation of finer digits (§2.5) must leave it exactly 50.123: a truncation done on the binary float
    (50.123 is 50.12299999… in binary) would give 50.1229."""
    (move,) = records(text)
    assert move["kind"] == "rapid" and close(move["end"], [50.123, 0.0, 0.0], 1e-9)
    back = records("G00 X-50.123\n")[0]["end"][0]
    assert close(back, -50.123, 1e-9)


def test_x16_bit_parameter_as_printed():
    """X16 example 1 (§3.2.9): ``G10L50; N2501 R 10000000; G11;`` sets bit 7 (LTM) of parameter 2501.
    In parameter input R is the raw integer value of the parameter (no decimal point, §3.2.9); for a bit
    parameter the eight digits are the bits 7..0, so 10000000 is a legal value and must be stored as is.
    (Example 2 of the same page runs in test_coordinates.py.)"""
    interp = Interpreter(read_program("G10L50\nN2501 R 10000000\nG11\nG00 X1\n"), get_dialect("gsk25i"))
    interp.state.parameters.raw.clear()
    toolpath = interp.run()
    assert interp.state.parameters.raw == {(2501, 0): 10000000}
    assert interp.state.block_hook is None and len(toolpath) == 1


def test_x20_g92_sets_the_current_position():
    """X20 (§3.2.13; the figures are lost). ``G92 X25.0 Z23.0``: "the tool nose coincides with the
    starting position of the program": the current position becomes X25 Z23; Y, not in the block, keeps
    its coordinate. From the machine origin, G90 X0 Y0 Z0 then goes to machine (-25, 0, -23)."""
    got = records("G92 X25.0 Z23.0\nG90 G00 X0 Y0 Z0\n")
    assert [r["end"] for r in got] == [[-25.0, 0.0, -23.0]]
    # ``G92 X600.0 Z1200.0`` with an external offset and G54 set (§3.2.13: "after the external workpiece zero
    # offset is set, the coordinate system isn't affected by the offset value: G92X100.0Z80.0 makes the
    # current position X=100, Z=80"). External (1, 1, 1) + G54 (9, 9, 9): work zero at machine (10, 10, 10).
    # After G92 at that point the position reads X600 Z1200, so work X0 is machine 10 - 600 = -590 and
    # work Z0 is 10 - 1200 = -1190; Y keeps the G54 origin (machine 10). GSK's G92 replaces the work system
    # until a G54-G59 selection (§3.2.13, docs/gcode.md), which brings back machine (10, 10, 10) for X0 Y0 Z0.
    text = ("G10 L2 P0 X1 Y1 Z1\nG10 L2 P1 X9 Y9 Z9\nG90 G54 G00 X0 Y0 Z0\nG92 X600.0 Z1200.0\n"
            "G00 X600.0 Z1200.0\nX0 Y0 Z0\nG54 X0 Y0 Z0\n")  # fmt: skip
    got = records(text)
    # "G00 X600 Z1200" is where the tool already is: no segment.
    assert [r["end"] for r in got] == [[10.0, 10.0, 10.0], [-590.0, 10.0, -1190.0], [10.0, 10.0, 10.0]]
    assert [r["line"] for r in got] == [3, 6, 7]



# G10 L50 sets P1880 = (-8, 5) mm, X and Y (in 0.0001 mm, no decimal point: §3.2.9); then the start point of
# the manual's example (1), G90 G00 X-10 Y10 (§3.2.7).
P1880 = "G10 L50\nN1880 P1 R-80000\nN1880 P2 R50000\nG11\nG90 G00 X-10 Y10\n"


@pytest.mark.parametrize(("text", "modal"), [
    ("G90;\nG60 X0Y0;\nG60 X100;\nG60 Y100;\nG04 X10;\nG00 X0Y0;\n", False),  # one-shot (standard)
    ("G90G60;\nX0Y0;\nX100;\nY100;\nG04 X10;\nG00 X0Y0;\n", True),             # modal (1870#0 MDL = 1)
])  # fmt: skip
def test_x14_one_shot_and_modal_g60_tables(text, modal):
    """X14's table (§3.2.7): the one-shot program and the modal one run the same path. Each G60 move
    rapids to the end less the overrun, end - P1880, dwells 1 s (§3.2.7) and rapids to the end (AB → 1 s →
    BC); an axis that does not move gets no overrun (§3.2.7: the overrun is for the final approach of a
    positioning). G04 in G60 mode is a plain one-shot (§3.2.7); G00 ends the mode."""
    dialect = replace(get_dialect("gsk25i"), g60_modal=True) if modal else get_dialect("gsk25i")
    got = [(r["kind"], r["end"] if r["kind"] != "dwell" else r["seconds"])
           for r in records(P1880 + text, dialect=dialect)]  # fmt: skip
    assert got == [
        ("rapid", [-10.0, 10.0, 0.0]),
        ("rapid", [8.0, -5.0, 0.0]), ("dwell", 1.0), ("rapid", [0.0, 0.0, 0.0]),          # X0Y0: (0+8, 0-5)
        ("rapid", [108.0, 0.0, 0.0]), ("dwell", 1.0), ("rapid", [100.0, 0.0, 0.0]),       # X100: X only
        ("rapid", [100.0, 95.0, 0.0]), ("dwell", 1.0), ("rapid", [100.0, 100.0, 0.0]),    # Y100: Y only
        ("dwell", 10.0),
        ("rapid", [0.0, 0.0, 0.0]),
    ]  # fmt: skip


def test_x29_g29_returns_uncommanded_axes_to_the_intermediate_point():
    """X29 example 2 (§3.3.3): ``G90 G0 X10 Y10; G91 G28 X20 Y20; G29 X30;`` — "return the reference
    position via the intermediate point (30, 30)"; then "G29 X30; Return from the reference position (60, 30)
    via the intermediate point (30, 30). ... in the incremental programming mode, the vector of X axial
    direction is 60". The manual contradicts itself: §3.3.3 says "when some axis isn't specified, it means
    the relative intermediate point in the axis doesn't have any move amount" (Y: zero increment from the
    intermediate point, so Y ends at 30) and then "other axes remain still". Issue 4 says to follow the
    reading the manual's own examples support: this example prints (60, 30) and passes (30, 30), so Y
    travels to its intermediate point too. X28 (§3.3.2) agrees: there N3 G29 X30 leaves Y at 10,
    where Y has no intermediate point stored (N2 was G28 X40 only).
    Expected: (10, 10); G28 via (30, 30) to the reference (0, 0); G29 via (30, 30) to (60, 30)."""
    got = [r["end"] for r in records("G90 G0 X10 Y10\nG91 G28 X20 Y20\nG29 X30\n")]
    assert got == [[10.0, 10.0, 0.0], [30.0, 30.0, 0.0], [0.0, 0.0, 0.0],
                   [30.0, 30.0, 0.0], [60.0, 30.0, 0.0]]  # fmt: skip

# ---------------------------------------------------------------------------------------- six-hole programs
# The manual's standard canned-cycle examples, transcribed line by line with their comments dropped (OCR
# splits such as "R-120 . P300" joined). Holes 1-5 return to R (G99), hole 6 to the initial level (G98);
# the literal program visits (300,-250), (300,-550), (300,-750), (1000,-750), (1000,-550), (1000,-750)
# (docs/gsk25i_examples.md: hole 6 repeats hole 4's position). Each ends G80; G28 G91 X0 Y0 Z0; M5; M30.
TAIL = "G80;\nG28 G91 X0 Y0 Z0 ;\nM5;\nM30;\n"
SIX_HOLES = "Y-550.;\nY-750.;\nX1000.;\nY-550.;\nG98 Y-750.;\n"
PROGRAMS = {
    # X31 G73 (§3.4.1): its own hole list.
    "X31": ("G73", "M3 S1500;\nG90 G99 G73 X0 Y0 Z-15. R-10. Q5 F120;\nY-50.;\nY-80.;\nX10.;\nY10.;\n"
                   "G98 Y75.;\n" + TAIL),
    # X32 G74 (§3.4.2): "X1000" without a point is 1000 mm (DPI = 1).
    "X32": ("G74", "M4 S100;\nG90 G99 G74 X300. Y-250. Z-150. R-120. P300 F120;\nY-550.;\nY-750.;\nX1000;\n"
                   "Y-550.;\nG98 Y-750.;\n" + TAIL),
    "X35": ("G81", "M3 S2000;\nG90 G99 G81 X300. Y-250. Z-150. R-10. F120;\n" + SIX_HOLES + TAIL),  # §3.4.5
    # X36 G82 (§3.4.6): "Y-550;" without a point.
    "X36": ("G82", "M3 S2000;\nG90 G99 G82 X300. Y-250. Z-150. R-100. P1000 F120;\nY-550;\nY-750;\nX1000.;\n"
                   "Y-550;\nG98 Y-750;\n" + TAIL),
    "X37": ("G83", "M3 S2000;\nG90 G99 G83 X300. Y-250. Z-150. R-100. Q15 F120;\nY-550;\nY-750;\nX1000;\n"
                   "Y-550;\nG98 Y-750;\n" + TAIL),  # §3.4.7
    # X38 G84 (§3.4.8): the garbled duplicate of the cycle line read once.
    "X38": ("G84", "M3 S100;\nG90 G99 G84 X300. Y-250. Z-150. R-120 P300 F120;\nY-550.;\nY-750.;\nX1000;\n"
                   "Y-550.;\nG98 Y-750.;\n" + TAIL),
    "X39": ("G85", "M3 S100;\nG90 G99 G85 X300. Y-250. Z-150. R-120. F120;\n" + SIX_HOLES + TAIL),  # §3.4.9
    # X40 G86 (§3.4.10): the last comment says "return to point R"; G98 returns to the initial level.
    "X40": ("G86", "M3 S2000;\nG90 G99 G86 X300. Y-250. Z-150. R-100. F120;\n" + SIX_HOLES + TAIL),
    "X43": ("G89", "M3 S100;\nG90 G99 G89 X300. Y-250. Z-150. R-120. P1000 F120;\n" + SIX_HOLES + TAIL),
}
HOLES = {"X31": [(0, 0), (0, -50), (0, -80), (10, -80), (10, 10), (10, 75)]}
STANDARD_HOLES = [(300, -250), (300, -550), (300, -750), (1000, -750), (1000, -550), (1000, -750)]
PECK_RETRACT = 0.5  # d: P2010 (G73) and P2011 (G83), 0.5 mm


class ExpectedPath:
    """Builds the expected (kind, end) list, dropping zero-length moves (the interpreter emits none)."""

    def __init__(self) -> None:
        self.position = (0.0, 0.0, 0.0)
        self.steps: list[tuple] = []

    def move(self, kind: str, x: float | None = None, y: float | None = None, z: float | None = None) -> None:
        x0, y0, z0 = self.position
        target = (x0 if x is None else float(x), y0 if y is None else float(y), z0 if z is None else float(z))
        if target != self.position:
            self.steps.append((kind, target))
            self.position = target

    def dwell(self, seconds: float) -> None:
        self.steps.append(("dwell", seconds))


def expected_hole(path: ExpectedPath, code: str, x: float, y: float, *, r: float, bottom: float, back: float,
                  q: float | None, dwell: float | None) -> None:
    """One hole by the manual's step list (§3.4; §3.4.1-§3.4.13): XY rapid at the current level, rapid
    to R, then the cycle's own steps; ``back`` is R (G99) or the initial level (G98)."""
    path.move("rapid", x, y)
    path.move("rapid", z=r)
    if code == "G73":  # feed Q deeper each time, rapid up d between pecks (§3.4.1)
        depth = r
        while depth > bottom:
            depth = max(depth - q, bottom)
            path.move("line", z=depth)
            if depth > bottom:
                path.move("rapid", z=depth + PECK_RETRACT)
        path.move("rapid", z=back)
    elif code == "G83":  # after each peck rapid to R, rapid down to d above the last depth (§3.4.7)
        depth = r
        while depth > bottom:
            if depth < r:
                path.move("rapid", z=r)
                path.move("rapid", z=depth + PECK_RETRACT)
            depth = max(depth - q, bottom)
            path.move("line", z=depth)
        path.move("rapid", z=back)
    elif code in ("G81", "G82", "G86"):  # feed in, [dwell], rapid out (G86 with the spindle stopped)
        path.move("line", z=bottom)
        if dwell:
            path.dwell(dwell)
        path.move("rapid", z=back)
    else:  # G74, G84 (tap in, dwell, reverse, tap out), G85 and G89 ([dwell], feed out): feed back to R
        path.move("line", z=bottom)
        if dwell:
            path.dwell(dwell)
        path.move("line", z=r)
        path.move("rapid", z=back)  # G98: rapid R → initial level


@pytest.mark.parametrize("example", sorted(PROGRAMS, key=lambda x: int(x[1:])))
def test_six_hole_programs_as_printed(example):
    code, text = PROGRAMS[example]
    words = dict((w[0], float(w[1:].rstrip("."))) for w in text.split(";\n")[1].split() if w[0] in "RZQP")
    r, bottom = words["R"], words["Z"]
    dwell = words["P"] / 1000 if "P" in words else None  # canned-cycle P is in ms
    expected = ExpectedPath()
    holes = HOLES.get(example, STANDARD_HOLES)
    for n, (x, y) in enumerate(holes):
        expected_hole(expected, code, x, y, r=r, bottom=bottom, back=0.0 if n == 5 else r, q=words.get("Q"),
                      dwell=dwell)  # fmt: skip
    # G28 G91 X0 Y0 Z0: the intermediate point is where the tool is (no move), then the reference position
    # (machine zero) in one rapid (§3.3.2).
    expected.move("rapid", 0, 0, 0)
    got = records(text, file=f"{example}.nc")
    actual = [("dwell", rec["seconds"]) if rec["kind"] == "dwell" else (rec["kind"], tuple(rec["end"]))
              for rec in got]
    assert len(actual) == len(expected.steps), (actual, expected.steps)
    for have, want in zip(actual, expected.steps, strict=True):
        assert have[0] == want[0] and close(have[1], want[1]), (have, want)
    assert all(rec["feed"] == 120.0 for rec in got if rec["kind"] == "line")  # F120 throughout
    assert got[-1]["line"] == text.count("\n") - 2  # the G28 block, before M5 and M30

