"""G65 macro instructions, M98/M99 and the part counter (HUST H4C-M manual §3.41, §3.39, §3.9.3).

The values of the manual's single-operation examples (Table 3-3 and the examples after it) are checked by
writing the result into a length word: a variable used in X counts least increments, so ``G01 X#10`` with
#10 = 1299 ends at X1.299.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from h4cm_helpers import ends, error, run

from cnc_gym.gcode import get_dialect
from cnc_gym.gcode.dialects.h4cm.options import H4cmOptions


def value(setup: str, var: int = 10, **kw) -> int:
    """The value of #var after ``setup`` (G65 blocks), read back through X in µm."""
    x = ends(f"G00 X-9.\n{setup}\nG01 X#{var} F100\nM02\n", **kw)[-1][0]
    return round(x * 1000)


@pytest.mark.parametrize(("setup", "expected"), [
    ("G65 L01 P#10 A150", 150),
    ("G65 L01 P#5 A99\nG65 L01 P#10 A-#5", -99),
    ("G65 L01 P#5 A99\nG65 L02 P#10 A1200 B#5", 1299),
    ("G65 L03 P#10 A100 B35", 65),
    ("G65 L01 P#10 A1200\nG65 L03 P#10 A#10 B5", 1195),
    ("G65 L04 P#10 A10 B25", 250),
    ("G65 L05 P#10 A130 B25", 5),  # 5.2 truncated
    ("G65 L05 P#10 A-130 B25", -5),  # toward zero
    ("G65 L11 P#10 A6 B100", 102),
    ("G65 L12 P#10 A6 B100", 4),
    ("G65 L13 P#10 A6 B100", 98),
    ("G65 L14 P#10 A49152 B1", 32769),  # 16-bit rotate: 0xC000 → 0x8001
    ("G65 L14 P#10 A-2 B1", -3),  # the bits above 16 (the sign) stay
    ("G65 L15 P#10 A3 B1", 32769),
    ("G65 L16 P#10 A13 B2", 52),
    ("G65 L17 P#10 A13 B2", 3),
    ("G65 L21 P#10 A1000", 31),  # √1000 = 31.6 truncated
    ("G65 L22 P#10 A-77", 77),
    ("G65 L23 P#10 A-17 B5", -2),  # -17 - trunc(-3.4)·5
    ("G65 L01 P#10 A300\nG65 L26 P#10 A7 B4", 525),  # 300·7/4
    ("G65 L31 P#10 A1000 B6000", 866),  # 1000·sin 60°
    ("G65 L32 P#10 A1000 B4500", 707),  # 1000·cos 45°
    ("G65 L34 P#10 A577 B1000", 2998),  # atan(0.577) = 29.98°; the manual prints the rounded 3000
])  # fmt: skip
def test_single_operations(setup, expected):
    assert value(setup) == expected


def test_fill_and_copy():
    # L6: #6 = 5, "P#10 A100 B#6" fills #10-#14 with 100 (the manual prints P#01; its results are #10-#14).
    fill = "G65 L01 P#6 A5\nG65 L06 P#10 A100 B#6"
    assert [value(fill, n) for n in (10, 14, 15)] == [100, 100, 0]
    # L7: #11-#15 = 10 … 50 copied to #1-#5.
    setup = "\n".join(f"G65 L01 P#{10 + n} A{10 * n}" for n in range(1, 6)) + "\nG65 L07 P#01 A#11 B5"
    assert [value(setup, n) for n in (1, 3, 5)] == [10, 30, 50]


def test_plc_registers_counters_and_bits():
    assert value("G65 L01 P#3 A7\nG65 L01 P#2 A31\nG65 L60 P#2 A#3\nG65 L50 P#10 A31") == 7
    counters = replace(get_dialect("h4cm"), options=H4cmOptions(plc_counters={10: 100}))
    assert value("G65 L56 P#10 A10", dialect=counters) == 100
    bits = replace(get_dialect("h4cm"), options=H4cmOptions(plc_bits={"I": 229 << 16}))
    assert value("G65 L51 P#10 A1", dialect=bits) == 229


@pytest.mark.parametrize(("op", "a", "b", "jumps"), [
    (81, 5, 5, True), (81, 5, 6, False), (82, 5, 6, True), (83, 6, 5, True), (83, 5, 5, False),
    (84, 4, 5, True), (85, 5, 5, True), (85, 4, 5, False), (86, 5, 5, True), (86, 6, 5, False),
])  # fmt: skip
def test_conditional_jumps(op, a, b, jumps):
    # E39: N30/N40 are skipped when the condition holds.
    text = (f"N10 G65 L01 P#1 A{a}\nN20 G65 L{op} P50 A#1 B{b}\nN30 G01 X100. F100\nN40 Y100.\n"
            "N50 G01 Z1.\nM02\n")
    assert ends(text) == ([(0.0, 0.0, 1.0)] if jumps else
                          [(100.0, 0.0, 0.0), (100.0, 100.0, 0.0), (100.0, 100.0, 1.0)])  # fmt: skip


def test_a_backward_jump_makes_a_loop():
    text = ("G65 L01 P#1 A0\nN1 G91\nG01 X1. F100\nG90\nG65 L02 P#1 A#1 B1\nG65 L84 P1 A#1 B3\nM02\n")
    assert [e[0] for e in ends(text)] == [1.0, 2.0, 3.0]


def test_user_alarms():
    # E40: G65 L99 P10 → Error 60; P outside 1-49 → Error 50.
    err = error("G01 X1. F100\nG65 L99 P10\n")
    assert (err.code, err.alarm, err.line) == ("user-alarm", 60, 2)
    assert error("G65 L99 P77\n").alarm == 50


def test_malformed_g65_blocks_are_refused_by_name():
    for text, code in (("G65 L02 P#1 A1", "missing-operand"), ("G65 L01 P#1 A1 B2", "unused-word"),
                       ("G65 L08 P#1 A1", "unknown-code"), ("G65 L01 P1 A1", "bad-macro-command"),
                       ("G65 L01 P#1 A1 X5.", "bad-macro-command"), ("G65 P#1 A1", "bad-macro-command"),
                       ("G65 L01 P#10000 A1", "bad-variable"), ("G65 L05 P#1 A1 B0", "division-by-zero"),
                       ("G65 L01 P#1 A99999999", "value-out-of-range"), ("G65 L80 P#1", "bad-macro-command"),
                       ("G65 L04 P#1 A9999999 B10", "overflow"), ("G01 G65 L01 P#1 A1", "bad-macro-command")):
        assert error(text + "\n").code == code, text


def test_variables_in_words_count_least_increments():
    # E41: "G01 U#12 F#03": U in µm, F in mm/min.
    text = "G65 L01 P#12 A2500\nG65 L01 P#3 A300\nG00 X1.\nG01 U#12 F#03\nM02\n"
    rows = run(text).to_records()
    assert rows[-1]["end"][0] == pytest.approx(3.5) and rows[-1]["feed"] == 300.0


def test_m98_p_l_and_nesting_of_five():
    sub = "O5\nG91\nG01 X1. F100\nG90\nM99\n"
    assert [e[0] for e in ends("M98 P05\nM98 P5 L3\nM02\n" + sub)] == [1.0, 2.0, 3.0, 4.0]
    chain = "".join(f"O{n}\nM98 P{n + 1}\nM99\n" for n in range(1, 6)) + "O6\nG01 X1. F100\nM99\n"
    assert ends("M98 P2\nM02\n" + chain) == [(1.0, 0.0, 0.0)]  # O2 … O6: five levels
    err = error("M98 P1\nM02\n" + chain)
    assert (err.code, err.alarm) == ("nesting", 24)
    assert error("M98 P1000\n").code == "bad-call"


def test_m99_in_the_main_program_restarts_and_the_counter_stops_it():
    text = "G10 P200 L3\nG91\nG01 X1. F100\nG90\nM99\n"
    # One pass by default (one part); restarting, the third part reaches the limit: ERROR 03.
    assert ends(text) == [(1.0, 0.0, 0.0)]
    err = error(text, main_m99="restart")
    assert (err.code, err.alarm, err.line) == ("part-count-limit", 3, 5)
    # G10 P201 clears the counter each pass: the loop runs until the block budget ends it.
    endless = "G10 P200 L3\nG10 P201\nG91\nG01 X1. F100\nG90\nM99\n"
    assert error(endless, main_m99="restart", max_blocks=50).code == "too-many-blocks"


def test_bad_options_are_one_line_config_errors():
    from cnc_gym.errors import ConfigError

    for kw in ({"plc_bits": {"X": 1}}, {"plc_registers": {300: 1}}, {"plc_counters": {1: 1.5}},
               {"interpolation_mode": 5}):  # fmt: skip
        with pytest.raises(ConfigError, match=r"^H4cmOptions\."):
            H4cmOptions(**kw)
