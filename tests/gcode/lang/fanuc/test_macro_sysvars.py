"""System variables (§3.7.3). Expected values follow from the programs' own
moves and settings, worked out in each test.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import pytest
from gcode_helpers import close, moves, program_error

from cnc_gym.gcode import interpret
from cnc_gym.toolpath import SegmentMode


def ends(text: str, **kw) -> list[tuple[float, ...]]:
    return [tuple(round(v, 6) for v in r["end"]) for r in moves(text, **kw)]


def last(text: str, **kw) -> tuple[float, ...]:
    return ends(text, **kw)[-1]


# --------------------------------------------------------------------------- modal information
def test_modal_groups_4001_to_4022():
    # After G01 G91 G18 G21 G55 G61: #4001 = 1, #4002 = 18, #4003 = 91, #4006 = 21, #4014 = 55, #4015 = 61.
    # They are read into commons, then the program goes back to G90 G17 G00 and moves to them.
    text = ("G01 G91 G18 G21 G55 G61 F100\n#101=#4001\n#102=#4002\n#103=#4003\n#104=#4006\n#105=#4014\n"
            "#106=#4015\nG90 G17 G54 G00 X#101 Y#102 Z#103\nX#104 Y#105 Z#106\n")  # fmt: skip
    assert ends(text) == [(1.0, 18.0, 91.0), (21.0, 55.0, 61.0)]


def test_modal_group_12_reports_g66_and_g67():
    text = "#101=#4012\nG66 P5\n#102=#4012\nG67\nG00 X#101 Y#102 Z#4012\nM30\nO5\nM99\n"
    assert ends(text) == [(67.0, 66.0, 67.0)]


def test_last_values_f_s_t_n_o_m():
    # #4109 F (program unit), #4119 S, #4120 T, #4114 the last N, #4115 the running program's O, #4113 the
    # last M code.
    text = ("O0042\nN7 G01 X1 F250 S1200 T3 M08\n#101=#4109\n#102=#4119\n#103=#4120\n#104=#4114\n"
            "#105=#4115\n#106=#4113\nG00 X#101 Y#102 Z#103\nX#104 Y#105 Z#106\n")  # fmt: skip
    assert ends(text)[1:] == [(250.0, 1200.0, 3.0), (7.0, 42.0, 8.0)]


def test_modal_and_position_variables_are_read_only():
    for index in (4001, 4120, 5001, 5021, 5041, 5061, 5083, 1000, 3011):
        err = program_error(f"#{index}=1\n")
        assert (err.code, err.alarm) == ("read-only-variable", 107), index


@pytest.mark.parametrize("index", [2507, 3005, 4023, 4100, 5006, 5106, 1036, 10401])
def test_numbers_between_the_ranges_do_not_exist(index):
    err = program_error(f"#1=#{index}\n")
    assert (err.code, err.alarm) == ("bad-variable", 107)


# --------------------------------------------------------------------------- positions
def test_position_variables_in_work_and_machine_coordinates():
    # G54 offset X100 Y200 (via #2501/#2601), G52 local X10. After G00 X5 Y6 Z7 in G54:
    # #5001 (block end, work) = (5, 6, 7); #5021 (machine) = (115, 206, 7); #5041 (work incl. offsets)
    # = machine − (G54 + G52) = (5, 6, 7).
    text = ("#2501=100\n#2601=200\nG54 G52 X10\nG00 X5 Y6 Z7\n#101=#5001\n#102=#5002\n#103=#5003\n"
            "#104=#5021\n#105=#5022\n#106=#5041\nG53 X#101 Y#102 Z#103\nG53 X#104 Y#105 Z#106\n")  # fmt: skip
    path = ends(text)
    assert path[0] == (115.0, 206.0, 7.0)
    assert path[1:] == [(5.0, 6.0, 7.0), (115.0, 206.0, 5.0)]


def test_position_variables_read_in_inch():
    # In G20 positions come back in inch: G00 X1 (inch) = 25.4 mm machine, #5001 = 1, #5021 = 1.
    text = "G20\nG00 X1\n#101=#5001\n#102=#5021\nG00 Y#101 Z#102\n"
    assert close(last(text), (25.4, 25.4, 25.4))


def test_skip_position_is_null_before_any_g31():
    # #5061 null: Y#5061 is dropped, only X moves.
    assert ends("G00 X1 Y#5061\n") == [(1.0, 0.0, 0.0)]


def test_servo_deviation_reads_zero():
    assert ends("#1=#5101+1\nG00 X#1\n") == [(1.0, 0.0, 0.0)]


# --------------------------------------------------------------------------- offsets
def test_work_offsets_2500_to_2906_read_and_write():
    # #2500 + 100·(axis-1) + k: k = 0 external, 1..6 G54..G59 (§3.7.3). #2702 = G55 Z.
    # External X 1 + G55 X 10 → G55 X0 goes to machine X11; G55 Z 5 → Z0 is machine Z5.
    text = "#2500=1\n#2502=10\n#2702=5\nG55 G00 X0 Y0 Z0\n#101=#2502+#2500\nG53 X#101 Y#2702\n"
    assert ends(text) == [(11.0, 0.0, 5.0), (11.0, 5.0, 5.0)]


def test_work_offsets_written_by_g10_are_read_back():
    assert last("G10 L2 P3 X7 Y8\nG00 X#2503 Y#2603\n") == (7.0, 8.0, 0.0)


def test_fourth_axis_work_offset_reads_null_and_cannot_be_written():
    assert ends("G00 X1 Y#2801\n") == [(1.0, 0.0, 0.0)]
    assert program_error("#2801=1\n").code == "unsupported-axis"


def test_tool_offsets_share_one_table():
    # #11001 (H1 geometry) and #2201 (H1 geometry, compatibility range) are the same memory; #10001 / #2001
    # H1 wear; #13001 D1 geometry, #12001 D1 wear. G10 L10 writes H geometry too.
    text = "#11001=20\n#2001=0.5\n#13002=4\n#12002=0.25\nG10 L10 P3 R7\nG00 X#2201 Y#10001 Z#11003\n" \
           "G00 X#13002 Y#12002\n"  # fmt: skip
    assert ends(text) == [(20.0, 0.5, 7.0), (4.0, 0.25, 7.0)]


def test_tool_offset_limits():
    # Wear within ±99.999 mm, geometry within ±999.999 (alarm 32 from the offset memory).
    assert program_error("#10001=100\n").code == "bad-offset-value"
    assert program_error("#11001=1000\n").code == "bad-offset-value"
    assert program_error("#11257=1\n").code == "bad-variable"  # H257 beyond the 256 offsets


def test_tool_offsets_are_in_program_units():
    # G20: #11001=1 stores 1 inch (25.4 mm); read back in G21 it is 25.4.
    assert last("G20\n#11001=1\nG21\nG00 X#11001\n") == (25.4, 0.0, 0.0)


# --------------------------------------------------------------------------- #3000-#3902
def test_user_alarm_3000():
    err = program_error("G00 X1\n#3000=12 (TOOL NOT FOUND)\n")
    assert (err.code, err.alarm, err.message, err.line) == ("user-alarm", 3012, "TOOL NOT FOUND", 2)
    assert program_error("#3000=7\n").message == "user alarm 7"
    assert program_error("#3000=201\n").code == "bad-variable"  # 0..200 (§3.7.3)


def test_message_stop_3006():
    # #3006=1 stops like M00: a 0 s dwell flagged exact stop.
    tp = interpret("G01 X1 F100\n#3006=1 (CHECK PART)\nX2\n")
    assert tp.kind.tolist() == [1, 3, 1]
    assert tp.dwell_s[1] == 0.0 and int(tp.modes[1]) & SegmentMode.EXACT_STOP


def test_3003_and_3004_read_back_and_range():
    assert last("#3003=3\n#3004=5\nG00 X#3003 Y#3004\n") == (3.0, 5.0, 0.0)
    assert program_error("#3003=4\n").code == "bad-variable"
    assert program_error("#3004=8\n").code == "bad-variable"


def test_nominal_clock_3001_3002():
    # G01 X100 at F6000 takes 1 s; a 2 s dwell; a 60 mm rapid at the nominal 6000 mm/min takes 0.6 s:
    # #3001 = 3600 ms. Writing #3001=0 restarts the count: another 1 s feed reads 1000. #3002 in hours.
    text = ("G01 X100 F6000\nG04 X2\nG00 X160\n#101=#3001\n#3001=0\nG01 X260\n#102=#3001\n#103=#3002\n"
            "G00 Y#101 Z#102\n")  # fmt: skip
    y, z = last(text)[1:]
    assert close(y, 3600.0, 1e-6) and close(z, 1000.0, 1e-6)
    hours = last("G01 X100 F6000\nG00 Y[#3002*3600000]\n")[1]
    assert close(hours, 1000.0, 1e-3)  # 1 s = 1/3600 h


def test_parts_counters():
    assert last("#3902=5\nG00 X#3902 Y#3901\n") == (5.0, 0.0, 0.0)
    assert program_error("#3901=-1\n").code == "bad-variable"


def test_plc_interface_variables():
    # Inputs #1000-#1035 read 0 (no PLC); outputs #1100-#1135 keep what the program writes (bits 0/1).
    assert last("#1100=1\n#1132=12345\nG00 X#1100 Y#1132 Z[#1000+#1032+1]\n") == (1.0, 12345.0, 1.0)
    assert program_error("#1100=2\n").code == "bad-variable"


def test_date_and_time_are_plausible():
    text = "G00 X[FIX[#3011/10000]] Y[FIX[#3012/10000]]\n"
    year, hour = last(text)[:2]
    assert 2000 <= year <= 2200 and 0 <= hour <= 23


def test_last_h_and_d_numbers():
    # #4111 / #4107: the H and D numbers last commanded (the compensation's state), here H2 and D3.
    assert last("G43 H2 Z1 D3\nG49\n#1=#4111\n#2=#4107\nG00 X#1 Y#2\n") == (2.0, 3.0, 1.0)


def test_skip_position_after_g31_and_extra_work_system_number():
    # G31 with no skip signal runs to its end point; #5061-#5063 hold it (work coordinates, §3.7.3).
    # #4130 is the G54.1 P number in force.
    assert last("G31 X10 Y5 F100\nG00 Z#5061\n") == (10.0, 5.0, 10.0)
    assert last("G54.1 P3\nG00 X#4130\n") == (3.0, 0.0, 0.0)


def test_tool_length_offset_5083():
    # G43 H1 with H1 = 12.5 (set through #11001): #5083 reads the offset in use, 12.5; after G49, 0.
    assert last("#11001=12.5\nG43 H1 Z0\n#1=#5083\nG49\n#2=#5083\nG00 X#1 Y#2\n")[:2] == (12.5, 0.0)
