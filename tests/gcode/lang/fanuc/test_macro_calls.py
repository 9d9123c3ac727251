"""Macro calls: G65, G66/G67, calls by G/M/T code, and the manual's worked macro programs (§3.7.3-
§3.7.8; worked examples X65-X78). Each test derives its expected path by hand from the manual's rules.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math

import pytest
from gcode_helpers import close, moves, program_error, records

from cnc_gym.errors import ConfigError
from cnc_gym.gcode import interpret
from cnc_gym.gcode.dialect import MacroCalls
from cnc_gym.toolpath import SegmentMode


def ends(text: str, **kw) -> list[tuple[float, ...]]:
    return [tuple(round(v, 6) for v in r["end"]) for r in moves(text, **kw)]


# --------------------------------------------------------------------------- arguments
SHOW_ARGS = "O9\n" + "".join(f"#{100 + i}=#{i}\n" for i in range(1, 34)) + "M99\n"


def locals_after(call: str) -> dict[int, float]:
    """Run ``call`` (a G65 P9 block), copying #1-#33 of the macro into #101-#133, then read them back by
    moving X to each non-null one (one segment per variable, in order)."""
    reads = "".join(f"IF[#{100 + i}NE#0]THEN#500={i}\nIF[#{100 + i}NE#0]GOTO{i}\nGOTO{100 + i}\n"
                    f"N{i} G91 G00 X#500 Y#{100 + i}\nG90\nN{100 + i} #500=#0\n"
                    for i in range(1, 34))  # fmt: skip
    out = {}
    position = (0.0, 0.0)
    for r in moves(call + "\n" + reads + "M30\n" + SHOW_ARGS):
        x, y = r["end"][0], r["end"][1]
        out[round(x - position[0])] = round(y - position[1], 6)
        position = (x, y)
    return out


def test_argument_specification_i():
    # §3.7.6: A B C → #1-#3, I J K → #4-#6, D E F → #7-#9, H #11, M #13, Q R S T U V W X Y Z → #17-#26.
    got = locals_after("G65 P9 A1 B2 C3 I4 J5 K6 D7 E8 F9 H11 M13 Q17 R18 S19 T20 U21 V22 W23 X24 Y25 Z26")
    assert got == {i: float(i) for i in (*range(1, 10), 11, 13, *range(17, 27))}


def test_argument_specification_ii():
    # §3.7.6: I/J/K groups 1..10 fill #4-#33 in threes; an omitted letter leaves its variable null
    # ("I1 K1 I2" puts I2 in #7).
    got = locals_after("G65 P9 A1 I4 J5 K6 I7 J8 K9 I10 K12 J14 I16 I19 I22 I25 I28 I31 J32 K33")
    # I10 K12 | J14 (J after K: new group 4 → #14) | I16 (group 5) | I19 | I22 | I25 | I28 | I31 J32 K33
    expected = (1, 4, 5, 6, 7, 8, 9, 10, 12, 14, 16, 19, 22, 25, 28, 31, 32, 33)
    assert got == {i: float(i) for i in expected}


def test_mixed_specifications_later_wins():
    # §3.7.6 (Fanuc original of the lost figure): A1.0 B2.0 I-3.0 I4.0 D5.0 → #1 1, #2 2, #4 -3,
    # #7 = 5.0: I4.0 (second I → group 2 → #7) is overwritten by the later D5.0 (#7).
    got = locals_after("G65 A1.0 B2.0 I-3.0 I4.0 D5.0 P9")
    assert got == {1: 1.0, 2: 2.0, 4: -3.0, 7: 5.0}


def test_null_and_expression_arguments():
    # A null variable drops its argument (the macro sees null); expressions are evaluated in the caller.
    got = locals_after("#1=2\nG65 P9 A#1 B#7 C[#1*3]")
    assert got == {1: 2.0, 3: 6.0}


def test_more_than_ten_ijk_groups_is_an_error():
    err = program_error("G65 P9 " + "I1 " * 11 + "\nM30\n" + SHOW_ARGS)
    assert err.code == "bad-call" and err.alarm == 17


# --------------------------------------------------------------------------- G65 semantics
def test_g65_opens_a_local_level_and_restores_it():
    # The caller's #1 = 7 survives the call; the macro sees only its argument (A3) and its own #2 is null.
    text = "#1=7\n#2=8\nG65 P10 A3\nG00 Y#1 Z#2\nM30\nO10\nG00 X#1 Z#2\n#1=99\nM99\n"
    assert ends(text) == [(3.0, 0.0, 0.0), (3.0, 7.0, 8.0)]


def test_g65_repeat_count_restarts_with_the_arguments():
    # G65 P L3: three passes; each starts from the arguments again, so #1 goes 1 → 2 in every pass and the
    # incremental move is +2 three times.
    text = "G91 G01 F100\nG65 P10 L3 A1\nM30\nO10\n#1=#1+1\nX#1\nM99\n"
    assert [e[0] for e in ends(text)] == [2.0, 4.0, 6.0]


def test_macro_nesting_four_levels_and_five_is_alarm_77():
    body = "".join(f"O{i}\nG91 G00 X1\nG65 P{i + 1}\nM99\n" for i in range(1, 4)) + "O4\nG00 X1\nM99\n"
    assert [e[0] for e in ends("G65 P1\nM30\n" + body)] == [1.0, 2.0, 3.0, 4.0]
    err = program_error("G65 P1\nM30\n" + body.replace("O4\nG00 X1\nM99\n", "O4\nG65 P5\nM99\nO5\nM99\n"))
    assert (err.code, err.alarm) == ("nesting", 77)


def test_macro_and_subprogram_nesting_are_counted_separately():
    # Four M98 levels inside four G65 levels: each kind has its own limit of 4 (§3.7.6, §3.7.7).
    macros = "".join(f"O{i}\nG65 P{i + 1}\nM99\n" for i in range(1, 4)) + "O4\nM98 P11\nM99\n"
    subs = "".join(f"O{i}\nM98 P{i + 1}\nM99\n" for i in range(11, 14)) + "O14\nG00 X1\nM99\n"
    assert ends("G65 P1\nM30\n" + macros + subs) == [(1.0, 0.0, 0.0)]


@pytest.mark.parametrize(
    ("text", "code", "alarm"),
    [
        ("G65 A1\n", "missing-program-number", 76),
        ("G65 P0\n", "bad-call", 17),
        ("G65 P12345\n", "bad-call", 17),
        ("G65 P9 L0\nO9\nM99\n", "bad-call", 17),
        ("G65 P77\n", "program-not-found", 59),
        ("G01 G65 P9 X1\nO9\nM99\n", "bad-call", 17),  # only arguments may follow G65
        ("G65 G66 P9\nO9\nM99\n", "group-conflict", None),
        ("#1=65\nG#1 P9\nO9\nM99\n", "bad-call", 17),  # G65 must be written literally
        ("G66 P78\n", "program-not-found", 59),  # checked at G66, not at the first move
    ],
)  # fmt: skip
def test_macro_call_errors(text, code, alarm):
    err = program_error(text)
    assert (err.code, err.alarm) == (code, alarm)


def test_arguments_take_decimal_points_and_signs_the_address_would_refuse():
    # D, H, M, T take no decimal point as addresses (Table 1-1), but as arguments (#7, #11, #13, #20) they do.
    got = locals_after("G65 P9 D1.5 H-2.5 M3.5 T0.25")
    assert got == {7: 1.5, 11: -2.5, 13: 3.5, 20: 0.25}


# --------------------------------------------------------------------------- G66 / G67
O9082 = "O9082\nG00 Z#18\nG01 Z#26\nG04 X#24\nG00 Z-[ROUND[#18]+ROUND[#26]]\nM99\n"


def test_g66_drilling_macro_x74():
    # §3.7.6 (the call's "X (point Z)" read as Z): G66 P9082 R-20 Z-10 X0.5 in G91. After each block
    # that moves, the macro rapids down 20, feeds down 10, dwells 0.5 s, rapids back up 30. The G66 block
    # itself and the M05 block (no motion) do not call; after G67 the move calls nothing.
    text = ("G90 G00 X0 Y0 Z50 F100\nG91\nG66 P9082 R-20 Z-10 X0.5\nX10\nY10\nM05\nG67\nX10\nM30\n"
            + O9082)  # fmt: skip
    path = records(text)
    drill = lambda x, y: [("rapid", (x, y, 30.0)), ("line", (x, y, 20.0)), ("dwell", 0.5),  # noqa: E731
                          ("rapid", (x, y, 50.0))]  # fmt: skip
    expected = [("rapid", (0.0, 0.0, 50.0)), ("rapid", (10.0, 0.0, 50.0)), *drill(10.0, 0.0),
                ("rapid", (10.0, 10.0, 50.0)), *drill(10.0, 10.0), ("rapid", (20.0, 10.0, 50.0))]  # fmt: skip
    got = [(r["kind"], r["seconds"] if r["kind"] == "dwell" else tuple(r["end"])) for r in path]
    assert got == expected


def test_multiple_modal_calls_x75_order():
    # §3.7.6 (figure lost; Fanuc order): a move in the main program calls the latest G66 (P9200); a
    # move inside P9200 calls the earlier one (P9100); moves inside P9100 call nothing. Incremental moves
    # make every block a segment; the order of source lines must be 1-1, 2-1, 1-2, 3-1, 2-1, 3-2, 2-1, 1-3.
    text = """G91 G00
G66 P9100
Z10 (1-1: line 3)
G66 P9200
Z15 (1-2: line 5)
G67
G67
Z-25 (1-3: line 8)
M30
O9100
X5 (2-1: line 11)
M99
O9200
Z6 (3-1: line 14)
Z7 (3-2: line 15)
M99
"""
    assert [r["line"] for r in moves(text)] == [3, 11, 5, 14, 11, 15, 11, 8]


def test_g66_arguments_are_fixed_at_the_g66_block():
    # "Local variables are not set each time a modal call is performed" (§3.7.6): every call starts from the
    # G66 block's arguments, whatever the macro did to its copy last time.
    text = "G91 G00\nG66 P20 A1\nX1\nX1\nG67\nM30\nO20\n#1=#1+1\nY#1\nM99\n"
    assert [e[1] for e in ends(text)] == [0.0, 2.0, 2.0, 4.0]


def test_g66_ignores_settings_and_null_axis_words():
    # G92 X0 sets a coordinate (no move); X#1 with #1 vacant is dropped (no move); X5 moves: one call.
    text = "G66 P5\nG92 X0\nX#1\nX5\nG67\nM30\nO5\nG91 G00 Z1\nG90\nM99\n"
    assert [r["line"] for r in moves(text)] == [4, 8]


def test_g66_calls_after_moves_that_cutter_compensation_holds_back():
    # With G41 the compensation emits a block's segment only when it has seen the next move; each of the
    # two moves (X20, Y10) still calls O5 once: its lines 9 and 10 appear twice each.
    text = "G41 D1 G01 X10 F100\nG66 P5\nX20\nY10\nG67\nG40 X0\nM30\nO5\nG91 G01 Z-1\nZ1\nG90\nM99\n"
    lines = interpret(text, tool_offsets={"D": {1: 2.0}}).line.tolist()
    assert lines.count(9) == 2 and lines.count(10) == 2


def test_g66_modal_state_shows_in_4012():
    text = "G65 P1\nG66 P2\nG65 P1\nG67\nG65 P1\nM30\nO1\nG91 G00 X#4012\nM99\nO2\nM99\n"
    assert [e[0] for e in ends(text)] == [67.0, 133.0, 200.0]


# --------------------------------------------------------------------------- calls by G, M and T codes
def test_macro_call_by_g_code():
    # Parameter 6050 = 12 → G12 calls O9010 like G65 (§3.7.6). The manual's body is garbled (X76); this
    # one mills the same kind of full circle: radius = |I| - wear of offset D (#[2000+#7]).
    body = "O9010\n#1=ABS[#4]-#[2000+#7]\nG91 G01 X#1 F100\nG03 I-#1\nG01 X-#1\nM99\n"
    text = "#2001=2\nG12 I10 D1\nM30\n" + body
    tp = interpret(text, macro_calls={"g_macro": {12: 9010}})
    # Radius 10 - 2 = 8: out along +X, one full CCW circle about the start, back.
    assert [tuple(e) for e in tp.end.tolist()] == [(8.0, 0.0, 0.0), (8.0, 0.0, 0.0), (0.0, 0.0, 0.0)]
    assert close(tp.radius[1], 8.0) and close(tp.sweep[1], 2 * math.pi)
    # Without the parameter G12 is not a GSK code.
    assert program_error(text).code == "unknown-code"


def test_code_is_ordinary_inside_its_own_macro():
    # Inside a program called by M06 (6071 → O9001), M06 is the ordinary tool change (§3.7.6).
    text = "T5 M06\nM30\nO9001\nG00 Z10\nM06\nM99\n"
    tp = interpret(text, macro_calls={"m_sub": {6: 9001}})
    assert [tuple(e) for e in tp.end.tolist()] == [(0.0, 0.0, 10.0)]


def test_subprogram_call_by_m_code_x77():
    # §3.7.6: M06 → O9001 saves and restores the modal groups 01 and 03 with #4001/#4003 and G#1 G#3.
    # The builder-specific M20-M23 and the G28 reference moves are left out (they need the machine's PLC);
    # what is tested is the save/restore and that the block's other words run before the call (T5).
    body = "O9001\n#1=#4001\n#3=#4003\nG91 G00 Z10\nZ-10\nG#1 G#3 M99\n"
    text = "G90 G01 X10 F100\nT5 M06\nX20\nM30\n" + body
    tp = interpret(text, macro_calls={"m_sub": {6: 9001}})
    assert [tuple(e) for e in tp.end.tolist()] == [(10, 0, 0), (10, 0, 10), (10, 0, 0), (20, 0, 0)]
    # The last move is G01 again (kind 1 = line) in G90 (absolute X20, not X30), with tool 5.
    assert int(tp.kind[-1]) == 1 and int(tp.tool[-1]) == 5


def test_m98_cannot_share_a_block_with_a_calling_m_code():
    err = program_error("G00 X1 M06 M98 P3\nM30\nO3\nM99\nO9001\nM99\n", macro_calls={"m_sub": {6: 9001}})
    assert err.code == "bad-call" and err.line == 1


def test_macro_call_by_m_code_with_arguments():
    text = "M50 A3 B4\nM30\nO9020\nG00 X#1 Y#2\nM99\n"
    assert ends(text, macro_calls={"m_macro": {50: 9020}}) == [(3.0, 4.0, 0.0)]


def test_subprogram_call_by_t_code():
    # 6001#0 TCS: "G00 X5 T7" ≡ "#149=7; G00 X5 M98 P9000" (§3.7.6). The T is not a tool selection;
    # inside O9000, T#149 is an ordinary T.
    text = "G00 X5 T7\nG00 X6\nM30\nO9000\nG00 Y#149\nT#149\nM99\n"
    tp = interpret(text, macro_calls=MacroCalls(t_sub=9000))
    assert [tuple(e) for e in tp.end.tolist()] == [(5, 0, 0), (5, 7, 0), (6, 7, 0)]
    assert tp.tool.tolist() == [0, 0, 7]


@pytest.mark.parametrize(
    "bad",
    [
        {"g_macro": {65: 9010}}, {"g_macro": {0: 9010}}, {"g_macro": {256: 9010}}, {"m_sub": {98: 9001}},
        {"m_macro": {6: 0}}, {"m_macro": {6: 9020}, "m_sub": {6: 9001}}, {"x_macro": {}}, "G12",
        {"g_macro": {i: 9010 for i in range(100, 111)}},
    ],
)  # fmt: skip
def test_bad_macro_call_tables(bad):
    with pytest.raises(ConfigError):
        interpret("G00 X1\n", macro_calls=bad)


# ------------------------------------------------------------------ worked macro programs (§3.7.3-§3.7.8)
O9081 = "O9081\n#3003=1\nG00 Z#18\nG01 Z#26\nG00 Z-[ROUND[#18]+ROUND[#26]]\n#3003=0\nM99\n"


def test_o9081_g81_equivalent_x65():
    # §3.7.3: G65 P9081 L2 R-20 Z-10 in G91 from Z50: down 20 rapid, 10 feed, up 30 rapid; twice.
    text = "G90 G00 X10 Y10 Z50 F100\nG91\nG65 P9081 L2 R-20 Z-10\nM30\n" + O9081
    assert ends(text) == [(10, 10, 50), (10, 10, 30), (10, 10, 20), (10, 10, 50), (10, 10, 30), (10, 10, 20),
                          (10, 10, 50)]  # fmt: skip


def test_o9084_tapping_with_3004_x66():
    # §3.7.3: #3004=7 makes feed hold, override and exact stop invalid for the tapping feed in and
    # out: those segments are OVERRIDE_LOCKED; the rapids before and after are not. M04 reverses the spindle
    # for the way out.
    body = ("O9084\n#3003=1\nG00Z#18\n#3004=7\nG01Z#26\nM05\nM04\nZ-#26\n#3004=0\nM05\nM03\nG00Z-#18\n"
            "#3003=0\nM99\n")  # fmt: skip
    text = "G90 G00 Z50 S500 M03 F100\nG91\nG65 P9084 R-20 Z-10\nM30\n" + body
    tp = interpret(text)
    z = [round(e[2], 6) for e in tp.end.tolist()]
    assert z == [50.0, 30.0, 20.0, 30.0, 50.0]
    locked = [bool(int(m) & SegmentMode.OVERRIDE_LOCKED) for m in tp.modes]
    assert locked == [False, False, True, True, False]
    assert tp.spindle_rpm.tolist() == [500.0, 500.0, 500.0, -500.0, 500.0]


def test_exact_stop_disabled_by_3004_bit_2():
    tp = interpret("G61 G01 X1 F100\n#3004=4\nX2\n#3004=0\nX3\n")
    exact = [bool(int(m) & SegmentMode.EXACT_STOP) for m in tp.modes]
    assert exact == [True, False, True]


def test_o9086_restores_the_distance_mode_x67():
    # §3.7.3: the macro switches to G91 and restores group 03 from #4003 with G#1 at M99. The caller's
    # X5 Z40 after the call is therefore absolute.
    body = "O9086\n#1=#4003\n#3003=1\nG00 G91 Z#18\nG01 Z#26\nM05\nG00 Z-[#18+#26]\nM03\n#3003=0\nG#1 M99\n"
    text = "G90 G00 Z50 F100 S100 M03\nG65 P9086 R-20 Z-10\nX5 Z40\nM30\n" + body
    assert ends(text) == [(0, 0, 50), (0, 0, 30), (0, 0, 20), (0, 0, 50), (5, 0, 40)]


O9200 = "O9200\n#101=#24\n#102=#25\n#100=0\nM99\n"
O9207 = """O9207
#30=#101
#31=#102
#32=1
WHILE[#32LEABS[#11]]DO1
#33=#1+360*[#32-1]/#11
#101=#30+#18*COS[#33]
#102=#31+#18*SIN[#33]
X#101 Y#102
#100=#100+1
#32=#32+1
END1
#101=#30
#102=#31
M99
"""


@pytest.mark.parametrize(
    ("h", "angles"),
    [(3, [30.0, 150.0, 270.0]), (-3, [30.0, -90.0, -210.0])],  # h < 0 counts clockwise
)  # fmt: skip
def test_bolt_circle_o9200_o9207_x71_x72(h, angles):
    # §3.7.6 (the X#101 Y#102 line and #100=#100+1 restored): datum (100, 50), R20, first hole at
    # A30, holes at A + 360(i-1)/H. After the macro the datum is restored and #100 counts the holes.
    call = f"G90 G00\nG65 P9200 X100 Y50\nG65 P9207 R20 A30 H{h}\nG00 X#101 Y#102 Z#100\nM30\n"
    text = call + O9200 + O9207
    holes = [(round(100 + 20 * math.cos(math.radians(a)), 4), round(50 + 20 * math.sin(math.radians(a)), 4))
             for a in angles]  # fmt: skip
    got = [(round(e[0], 4), round(e[1], 4)) for e in ends(text)]
    assert got[:3] == holes
    assert ends(text)[-1] == (100.0, 50.0, 3.0)


O9203 = """O9203
#2=#101
#3=#102
#5=4
#8=0
WHILE[#5LE31]DO1
IF[#[#5]EQ#0]GOTO9001
DO2
#8=#8+#[#5]
#101=#2+#8*COS[#1]
#102=#3+#8*SIN[#1]
X#101 Y#102
#100=#100+1
#[#5+2]=#[#5+2]-1
IF[#[#5+2]LE0]GOTO9002
END2
N9002 #5=#5+3
END1
N9001 #101=#2
#102=#3
M99
"""


def test_unequal_pitch_line_o9203_x73():
    # §3.7.6 (the second "#2=#102" read as #3=#102, "D01"/"D02" as DO1/DO2, "LEO" as LE0): spec II
    # arguments I1 K1 I2 K2 …: K holes at pitch I, group after group, along angle A from the datum.
    # A30, I10 K2, I5 K3 → distances 10, 20, 25, 30, 35.
    text = "G90 G00\nG65 P9200 X1 Y2\nG65 P9203 A30 I10 K2 I5 K3\nG00 Z#100\nM30\n" + O9200 + O9203
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    expected = [(round(1 + d * c, 4), round(2 + d * s, 4)) for d in (10, 20, 25, 30, 35)]
    got = ends(text)
    assert [(round(x, 4), round(y, 4)) for x, y, _ in got[:5]] == expected
    assert got[-1][2] == 5.0  # #100 counted five holes


def test_combined_holes_sample_2():
    # §3.7.6 with G00 positioning instead of G81: G66 P9207 makes every hole O9203 moves to the centre
    # of a bolt circle (O9207 reads the datum #101/#102 that O9203 has just set, and restores it).
    # Line A0 I10 K2 from (0, 0): holes at X10 and X20; each gets two holes of radius 2 at 0° and 180°.
    text = ("G90 G00\nG65 P9200 X0 Y0\nG66 P9207 R2 A0 H2\nG65 P9203 A0 I10 K2\nG67\nG00 Z#100\nM30\n"
            + O9200 + O9207 + O9203)  # fmt: skip
    got = [(round(x, 6), round(y, 6), z) for x, y, z in ends(text)]
    assert got == [(10, 0, 0), (12, 0, 0), (8, 0, 0), (20, 0, 0), (22, 0, 0), (18, 0, 0), (18, 0, 6)]


O9802 = """O9802
#27=#[2000+#7]
#28=#6+#27
#29=#5-2*#28
#30=2*#27*#23/100
#31=FUP[#29/#30]
#32=#29/#31
#10=#24+#28
#11=#25+#28
#12=#24+#4-#28
#13=#26+#26+#6
G00 X#10 Y#11
Z#18
#14=18
DO1
#14=#14-#17
IF[#14GE13]GOTO1
#14=#13
N1 G01 Z#14 F#8
X#12 F#9
#15=1
WHILE[#15LE#31]DO2
Y[#11+#15*#32]
IF[[#15AND1]EQ0]GOTO2
X#10
GOTO3
N2 X#12
N3 #15=#15+1
END2
G00 Z#18
X#10 Y#11
IF[#14LE#13]GOTO4
G01 Z[#14+1] F[8*#8]
END1
N4 M99
"""


def test_grooving_o9802_runs_to_a_finite_path():
    # §3.7.8, quality C (heavily garbled; "D01"/"GOTO02"/"EQO" normalised, the lost DO1 put before the
    # depth step). Not a geometry oracle: it must run to a finite path or a clear error, never hang.
    # The body reads the width percentage from #23 (W), the call line prints T: W is passed.
    text = "#2001=5\nG90\nG65 P9802 X0 Y0 Z-10 R2 Q4 I100 J40 K1 W60 D1 F300 E100\nM30\n" + O9802
    tp = interpret(text, max_blocks=100_000)
    assert len(tp) > 0 and bool((abs(tp.end) < 1e4).all())
