"""Work offsets: G10 L2, G54-G59, G52, G53, G92, and inch/mm (§3.2.9-§3.2.14, §3.2.19, §3.2.20).

The machine starts at the machine origin with every offset zero; expected machine coordinates are
program value + offsets, worked out by hand per test.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import pytest
from gcode_helpers import close, moves, program_error

SET_G54_G55 = "G10 L2 P1 X20 Y20 Z20\nG10 L2 P2 X30 Y30 Z30\n"


def ends(text: str) -> list[list[float]]:
    return [r["end"] for r in moves(text)]


def test_worked_example_x17_axes_not_commanded_keep_their_machine_position():
    # §3.2.10: G54 origin at machine (20, 20, 20), G55 at (30, 30, 30).
    #   G0 G54 X50 Y50 Z50 → machine (70, 70, 70)
    #   G55 X100 Y100      → X, Y to 100 in G55 = machine 130; Z is not commanded and "the actual position
    #                        of the machine does not change" (§3.2.10): machine Z stays 70 (absolute 40).
    #                        The manual's table prints 30/60 for Z, which contradicts its own rule.
    #   X120 Z80           → machine (150, 130, 110)
    assert ends(SET_G54_G55 + "G0 G54 X50 Y50 Z50\nG55 X100 Y100\nX120 Z80\n") == [
        [70.0, 70.0, 70.0], [130.0, 130.0, 70.0], [150.0, 130.0, 110.0],
    ]  # fmt: skip


def test_worked_example_x18_switching_wcs_with_rapid():
    # §3.2.10 with G55 = (30, 30, 30) and G56 = (-10, 5, 2): N10 → (100+30, 20+30, Z untouched 0);
    # N20 → X 80.5-10 = 70.5, Y untouched 50, Z 25.5+2 = 27.5.
    text = "G10 L2 P2 X30 Y30 Z30\nG10 L2 P3 X-10 Y5 Z2\nN10 G55 G90 G00 X100 Y20\nN20 G56 X80.5 Z25.5\n"
    assert ends(text) == [[130.0, 50.0, 0.0], [70.5, 50.0, 27.5]]


def test_g10_in_g91_adds_to_the_offset_and_p0_is_the_external_offset():
    # §3.2.10: G90 sets, G91 adds. P0 (external) shifts every work system.
    text = SET_G54_G55 + "G91 G10 L2 P1 X5 Z-1\nG90\nG10 L2 P0 X1 Y2 Z3\nG54 G00 X0 Y0 Z0\nG55 X0 Y0 Z0\n"
    assert ends(text) == [[26.0, 22.0, 22.0], [31.0, 32.0, 33.0]]


def test_g10_changes_the_active_system_at_once():
    assert ends("G54\nG10 L2 P1 X20\nG00 X1\n") == [[21.0, 0.0, 0.0]]


def test_all_six_work_systems():
    setup = "".join(f"G10 L2 P{p} X{10 * p} Y{-p}\n" for p in range(1, 7))
    text = setup + "".join(f"G{53 + p} G00 X1 Y1\n" for p in range(1, 7))
    assert ends(text) == [[10.0 * p + 1, 1.0 - p, 0.0] for p in range(1, 7)]


def test_g52_local_system_applies_in_every_wcs_and_is_not_cumulative():
    # §3.2.14: G52 IP sets a local origin in the current work system; a new G52 replaces the old;
    # G52 X0 cancels on X only.
    text = SET_G54_G55 + ("G54 G52 X5 Y-5\nG00 X0 Y0\nG52 X5 Y-5\nG00 X1 Y1\nG55 X0 Y0\n"
                          "G52 X0\nG00 X0 Y0\n")  # fmt: skip
    assert ends(text) == [[25.0, 15.0, 0.0], [26.0, 16.0, 0.0], [35.0, 25.0, 0.0], [30.0, 25.0, 0.0]]


def test_g53_moves_in_machine_coordinates_at_rapid():
    # §3.2.12: G53 IP_ is a rapid to machine coordinates, one-shot; offsets are bypassed.
    out = moves(SET_G54_G55 + "G54 G01 X0 Y0 F500\nG53 X10 Y10\nX1\n")
    assert [r["kind"] for r in out] == ["line", "rapid", "line"]  # G53 does not change the modal G01
    assert [r["end"] for r in out] == [[20.0, 20.0, 0.0], [10.0, 10.0, 0.0], [21.0, 10.0, 0.0]]


def test_g53_with_g00_or_g01_in_the_block_is_a_rapid_and_sets_the_mode():
    out = moves("G01 F100\nG53 G01 X5\nY3\n")
    assert [r["kind"] for r in out] == ["rapid", "line"]


def test_g53_is_ignored_in_g91():
    # §3.2.12: "When an incremental command (G91) is specified, the G53 command is ignored."
    assert ends("G00 X1\nG91 G53 X10 Y10\nG00 X1\n") == [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]


def test_g92_floating_system_and_g54_cancels_it():
    # §3.2.13: G92 gives the current position the programmed coordinates; selecting G54..G59 drops it.
    text = "G10 L2 P1 X20 Y20 Z20\nG54 G00 X10 Y10\nG92 X0 Y0\nG00 X5 Y5\nG54 X5 Y5\n"
    # G54 X10 Y10 → machine (30, 30, 0); G92 makes that (0, 0); X5 Y5 → (35, 35); after G54: (25, 25).
    assert ends(text) == [[30.0, 30.0, 0.0], [35.0, 35.0, 0.0], [25.0, 25.0, 0.0]]


def test_g92_on_some_axes_keeps_the_others_and_clears_their_g52_only():
    # §3.2.15: G92 with some axes does not cancel the G52 offsets of the unspecified axes.
    text = "G10 L2 P1 X20 Y20 Z20\nG54 G52 X5 Y5\nG00 X0 Y0\nG92 X0\nG00 X1 Y1\n"
    # After G52: X0 Y0 → machine (25, 25). G92 X0: machine X 25 is now X0 (local X cleared); Y keeps
    # G54 + G52: Y1 → 20 + 5 + 1 = 26.
    assert ends(text) == [[25.0, 25.0, 0.0], [26.0, 26.0, 0.0]]


def test_offsets_and_positions_in_inches():
    # G20: offsets programmed in inches are stored as mm; positions too.
    text = "G20\nG10 L2 P1 X1\nG54 G00 X1\nG52 Y0.5\nG00 Y0\nG92 Z1\nG00 Z0\n"
    out = ends(text)
    assert close(out[0], [50.8, 0.0, 0.0]) and close(out[1], [50.8, 12.7, 0.0])
    assert close(out[2], [50.8, 12.7, -25.4])  # G92 Z1 at machine Z 0: Z0 is 1 in = 25.4 mm below


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("G10 P1 X1\n", "missing-value", 5),
        ("G10 L3 P1 X1\n", "bad-g10", 31),
        ("G10 L2 X1\n", "bad-g10", 31),
        ("G10 L2 P7 X1\n", "bad-g10", 31),
        ("G10 L2 P1.5 X1\n", "bad-g10", 31),
        ("G10 L2 P1 R5\n", "unused-word", None),
        ("G10 L10 P0 R5\n", "bad-offset-number", 30),  # H00 is always 0 (compensation's offsets.py)
        ("G10 L20 P49 X1\n", "bad-g10", 31),
        ("G92 G01 X1 F100\n", "axis-word-conflict", None),
        ("G04 G00 X1\n", "axis-word-conflict", None),
        ("G53 G02 X1 I1 F100\n", "bad-combination", None),
        ("G54.1 P49\n", "bad-offset-number", 30),
    ],
)
def test_offset_errors(text, code, alarm):
    err = program_error(text)
    assert (err.code, err.alarm) == (code, alarm)
