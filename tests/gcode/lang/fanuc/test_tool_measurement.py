"""G37 automatic tool length measurement (manual §3.5.6, example X61) with the simulated instrument.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import pytest

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.gcode import interpret
from cnc_gym.gcode.settings import ToolMeasurement
from cnc_gym.toolpath import SegmentKind, SegmentMode

# X61 (§3.5.6), then two probes that print the H01 wear (#10001) and geometry (#11001) as X and Y.
X61 = "G92 Z760.0 X1100.0;\nG00 G90 X850.0;\nH01;\nG37 Z200.0;\nG00 Z204.0;\n"
PROBE = "G01 X#10001 Y#11001 F100\n"
INSTRUMENT = {"signal_at": {1: 198.0}, "decel_mm": 10.0, "band_mm": 5.0}


def test_x61_signal_at_z198_lowers_the_offset_by_2():
    # G92 at machine (0, 0, 0) makes it work (1100, ?, 760): work → machine is −1100 on X, −760 on Z.
    # G00 X850 → machine X −250. G37 Z200: rapid down to r = 10 mm before Z200 (work Z210, machine −550),
    # then the measurement feed P2651 = 1000 mm/min until the signal at work Z198 (machine −562), where
    # the tool stops. Offset H01 += 198 − 200 = −2 (§3.5.6), in the wear value (memory C). G00 Z204 →
    # machine −556.
    tp = interpret(X61 + PROBE, tool_measurement=INSTRUMENT)
    assert tp.kind.tolist()[:4] == [SegmentKind.RAPID, SegmentKind.RAPID, SegmentKind.LINE, SegmentKind.RAPID]
    assert tp.end[0].tolist() == [-250.0, 0.0, 0.0]
    assert tp.end[1].tolist() == [-250.0, 0.0, -550.0] and tp.line[1] == 4
    assert tp.end[2].tolist() == pytest.approx([-250.0, 0.0, -562.0]) and tp.feed[2] == 1000.0
    assert tp.modes[2] & SegmentMode.EXACT_STOP  # the signal stops the axis
    assert tp.end[3].tolist() == pytest.approx([-250.0, 0.0, -556.0])
    # probe: X = H01 wear = −2, Y = H01 geometry = 0 (work coordinates → machine −1100 − 2, 0 − 0)
    assert tp.end[4].tolist() == pytest.approx([-1102.0, 0.0, -556.0])


def test_the_parameters_can_come_from_g10_l50():
    # P2652 r = 10 mm and P2653 e = 5 mm in 0.0001 mm units (R takes no decimal point); P2651 500 mm/min.
    text = "G10 L50;\nN2651 R500;\nN2652 R100000;\nN2653 R50000;\nG11;\n" + X61 + PROBE
    tp = interpret(text, tool_measurement={"signal_at": {1: 198.0}})
    line = tp.kind == SegmentKind.LINE
    assert tp.feed[line].tolist()[0] == 500.0
    assert tp.end[-1, 0] == pytest.approx(-1102.0)


def test_an_instrument_that_does_not_list_the_tool_signals_at_the_position():
    # No entry for H01: the tool length is right, the signal comes at Z200 and nothing changes.
    tp = interpret(X61 + PROBE)
    assert tp.end[-2].tolist() == pytest.approx([-250.0, 0.0, -556.0])
    assert tp.end[-1].tolist() == pytest.approx([-1100.0, 0.0, -556.0])


def test_g37_with_g43_in_force_keeps_the_vector_until_h_is_given_again():
    # H01 = 20 applied by G43: work Z = machine Z − 20. After G37 changes H01's wear by −2, the next Z
    # move still uses the old vector (our choice, like G10); G43 H01 again picks up 18.
    text = ("G90 G00 Z300\nG43 H01 Z300\nG37 Z200\nG00 Z250\nG43 H01 Z250\n")
    tp = interpret(text, tool_offsets={"H": {1: 20.0}},
                   tool_measurement={"signal_at": {1: 198.0}, "decel_mm": 10.0, "band_mm": 5.0})  # fmt: skip
    assert tp.end[-2, 2] == pytest.approx(270.0)  # 250 + 20 (old vector)
    assert tp.end[-1, 2] == pytest.approx(268.0)  # 250 + 18


@pytest.mark.parametrize(
    ("signal", "message"),
    [
        (206.0, "before the permitted band"),  # B (Z210) to C (Z205): too early
        (212.0, "during the rapid approach"),  # above B: the tool would meet the instrument at rapid
        (194.0, "no approach-end signal by Z195"),  # beyond F = Z195
    ],
)
def test_signals_outside_the_band_are_alarm_80(signal, message):
    with pytest.raises(ProgramError) as err:
        interpret(X61, tool_measurement={**INSTRUMENT, "signal_at": {1: signal}})
    assert err.value.code == "g37-signal" and err.value.alarm == 80 and err.value.line == 4
    assert message in str(err.value)


@pytest.mark.parametrize(
    ("text", "code"),
    [
        ("H01;\nG37 Z200 H01;\n", "g37-h-in-block"),  # note 1 (§3.5.6): alarm
        ("G37 Z200;\n", "g37-no-h"),
        ("H01;\nG37 X10 Z200;\n", "g37-axis"),
        ("H01;\nG37;\n", "g37-axis"),
        ("H01;\nG91 G37 Z-10;\n", "g37-incremental"),
        ("H01;\nG68 X0 Y0 R30;\nG37 Z-10;\n", "bad-combination"),
        ("H01;\nG37 Z0;\n", "g37-signal"),  # already at the measurement position
    ],
)
def test_g37_restrictions(text, code):
    with pytest.raises(ProgramError) as err:
        interpret(text)
    assert err.value.code == code


def test_tool_measurement_settings_are_validated():
    assert ToolMeasurement.coerce(None) == ToolMeasurement()
    for bad in ({"signal_at": {0: 1.0}}, {"signal_at": {1: "x"}}, {"band_mm": -1}, {"feed_mm_min": 0},
                {"speed": 1}, 3):  # fmt: skip
        with pytest.raises(ConfigError):
            interpret("G0 X1\n", tool_measurement=bad)
